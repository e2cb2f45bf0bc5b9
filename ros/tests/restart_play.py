#!/usr/bin/python3
"""Plays a bag into ROS 1 in real time as the drivers publish it, with some drivers restarting.

restart_play.py BAG TOPIC:FROM_S:SECONDS[,...]

Each named topic's publisher goes away FROM_S seconds after the bag's first message and a new one
(a restarted driver: a new connection, its header seq from 0 again) comes back SECONDS later; what
the bag holds in between is not sent. Messages go out as recorded (raw, not decoded): a Python
player keeps up with clouds of driver size. Waits for every topic's subscriber (the node) first.
"""
import sys
import time

import genpy
import rosbag
import rospy


def raw_type(datatype, md5sum, full_text):
    """A message class that rospy publishes as the bag's bytes."""

    class Raw(genpy.Message):
        __slots__ = ["data"]
        _type, _md5sum, _full_text, _has_header, _slot_types = datatype, md5sum, full_text, False, ["uint8[]"]

        def __init__(self, data=b""):  # pylint: disable=super-init-not-called
            self.data = data

        def serialize(self, buff):
            buff.write(self.data)

    return Raw


def main():
    bag_path, spec = sys.argv[1], sys.argv[2]
    restarts = {}
    for item in spec.split(","):
        topic, from_s, seconds = item.rsplit(":", 2)
        restarts[topic] = (float(from_s), float(from_s) + float(seconds))
    rospy.init_node("restart_play", anonymous=True, disable_signals=True)
    bag = rosbag.Bag(bag_path)
    types, publishers = {}, {}
    for c in bag._get_connections():
        types[c.topic] = raw_type(c.datatype, c.md5sum, c.msg_def)

    def advertise(topic):
        publishers[topic] = rospy.Publisher(topic, types[topic], queue_size=100)

    for topic in types:
        advertise(topic)
    deadline = time.time() + 30
    while any(p.get_num_connections() == 0 for p in publishers.values()):
        if time.time() > deadline:
            sys.exit("restart_play: no subscriber on " + ", ".join(t for t, p in publishers.items()
                                                                 if p.get_num_connections() == 0))
        time.sleep(0.1)

    t0_bag, t0_wall = bag.get_start_time(), time.time()
    seq = {}  # restarted drivers count their seq from 0
    for topic, (datatype, data, md5sum, pos, pytype), t in bag.read_messages(raw=True):
        at = t.to_sec() - t0_bag
        wait = t0_wall + at - time.time()
        if wait > 0:
            time.sleep(wait)
        for other, (stop, back) in restarts.items():
            if other not in publishers and at >= back - 1.0:
                advertise(other)  # the driver is up again a second before its first message
        if topic in restarts:
            stop, back = restarts[topic]
            if stop <= at < back:
                if topic in publishers and at < back - 1.0:
                    publishers.pop(topic).unregister()
                continue
            if at >= back:
                n = seq.get(topic, 0)
                seq[topic] = n + 1
                data = n.to_bytes(4, "little") + data[4:]  # std_msgs/Header.seq leads the message
        publishers[topic].publish(types[topic](data))
    time.sleep(1.0)  # the last messages leave before the publishers go


if __name__ == "__main__":
    main()
