#!/usr/bin/env python3
"""A minimal ROS1 master (XML-RPC, Python standard library only) for smoke-testing mmlio_node on
machines without roscore: parameters, topic registration with publisherUpdate notifications,
getPublishedTopics / getTopicTypes. No services lookup, no parameter subscriptions.

    python3 ros/tools/mini_rosmaster.py --port 11311 &
    export ROS_MASTER_URI=http://localhost:11311
"""
import argparse
import os
import threading
import xmlrpc.client
from socketserver import ThreadingMixIn
from xmlrpc.server import SimpleXMLRPCServer


class Server(ThreadingMixIn, SimpleXMLRPCServer):
    daemon_threads = True
    allow_reuse_address = True


class Master:
    def __init__(self, uri):
        self.uri = uri
        self.lock = threading.Lock()
        self.params = {}
        self.publishers = {}   # topic -> {caller_id: api}
        self.subscribers = {}  # topic -> {caller_id: api}
        self.types = {}        # topic -> datatype
        self.services = {}

    # --- parameters ---
    def _key(self, caller_id, key):
        if key.startswith('/'):
            return key
        ns = caller_id.rsplit('/', 1)[0] if '/' in caller_id else ''
        return ns + '/' + key

    def setParam(self, caller_id, key, value):
        with self.lock:
            key = self._key(caller_id, key).rstrip('/')
            if isinstance(value, dict):
                for k, v in value.items():
                    self.params[key + '/' + k] = v
            else:
                self.params[key] = value
        return [1, 'ok', 0]

    def getParam(self, caller_id, key):
        with self.lock:
            key = self._key(caller_id, key).rstrip('/')
            if key in self.params:
                return [1, 'ok', self.params[key]]
            sub = {k[len(key) + 1:]: v for k, v in self.params.items() if k.startswith(key + '/')}
            if sub:
                return [1, 'ok', sub]
        return [-1, 'parameter %s is not set' % key, 0]

    def hasParam(self, caller_id, key):
        return [1, 'ok', self.getParam(caller_id, key)[0] == 1]

    def deleteParam(self, caller_id, key):
        with self.lock:
            self.params.pop(self._key(caller_id, key), None)
        return [1, 'ok', 0]

    def searchParam(self, caller_id, key):
        return [-1, 'not found', 0]

    def subscribeParam(self, caller_id, caller_api, key):
        return [1, 'ok', self.getParam(caller_id, key)[2] if self.getParam(caller_id, key)[0] == 1 else {}]

    def unsubscribeParam(self, caller_id, caller_api, key):
        return [1, 'ok', 1]

    def getParamNames(self, caller_id):
        with self.lock:
            return [1, 'ok', list(self.params)]

    # --- master ---
    def getPid(self, caller_id):
        return [1, 'ok', os.getpid()]

    def getUri(self, caller_id):
        return [1, 'ok', self.uri]

    def _notify(self, topic):
        pubs = list(self.publishers.get(topic, {}).values())
        for api in list(self.subscribers.get(topic, {}).values()):
            def call(api=api):
                try:
                    xmlrpc.client.ServerProxy(api).publisherUpdate('/master', topic, pubs)
                except Exception as e:  # a node that went away
                    print('publisherUpdate to %s failed: %s' % (api, e), flush=True)
            threading.Thread(target=call, daemon=True).start()

    def registerPublisher(self, caller_id, topic, datatype, caller_api):
        with self.lock:
            self.publishers.setdefault(topic, {})[caller_id] = caller_api
            self.types.setdefault(topic, datatype)
            subs = list(self.subscribers.get(topic, {}).values())
            self._notify(topic)
        return [1, 'ok', subs]

    def unregisterPublisher(self, caller_id, topic, caller_api):
        with self.lock:
            self.publishers.get(topic, {}).pop(caller_id, None)
            self._notify(topic)
        return [1, 'ok', 1]

    def registerSubscriber(self, caller_id, topic, datatype, caller_api):
        with self.lock:
            self.subscribers.setdefault(topic, {})[caller_id] = caller_api
            if datatype != '*':
                self.types.setdefault(topic, datatype)
            pubs = list(self.publishers.get(topic, {}).values())
        return [1, 'ok', pubs]

    def unregisterSubscriber(self, caller_id, topic, caller_api):
        with self.lock:
            self.subscribers.get(topic, {}).pop(caller_id, None)
        return [1, 'ok', 1]

    def registerService(self, caller_id, service, service_api, caller_api):
        with self.lock:
            self.services[service] = service_api
        return [1, 'ok', 0]

    def unregisterService(self, caller_id, service, service_api):
        with self.lock:
            self.services.pop(service, None)
        return [1, 'ok', 1]

    def lookupService(self, caller_id, service):
        with self.lock:
            if service in self.services:
                return [1, 'ok', self.services[service]]
        return [-1, 'no provider', '']

    def getPublishedTopics(self, caller_id, subgraph):
        with self.lock:
            return [1, 'ok', [[t, self.types.get(t, '*')] for t, p in self.publishers.items() if p]]

    def getTopicTypes(self, caller_id):
        with self.lock:
            return [1, 'ok', [[t, d] for t, d in self.types.items()]]

    def getSystemState(self, caller_id):
        with self.lock:
            pubs = [[t, list(p)] for t, p in self.publishers.items() if p]
            subs = [[t, list(s)] for t, s in self.subscribers.items() if s]
            return [1, 'ok', [pubs, subs, [[s, []] for s in self.services]]]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--port', type=int, default=11311)
    args = parser.parse_args()
    server = Server(('127.0.0.1', args.port), logRequests=False, allow_none=True)
    server.register_instance(Master('http://127.0.0.1:%d/' % args.port))
    print('mini_rosmaster on http://127.0.0.1:%d/' % args.port, flush=True)
    server.serve_forever()


if __name__ == '__main__':
    main()
