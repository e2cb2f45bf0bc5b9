"""What the live node tests' checks share: every check printed, the run failed at the end if any did.
From a shell: python3 -m live_checks driver_restarts|second_pass|replayed WORK FOLDER [ATE RUN_ATE]."""
import json
import math
import sys

errors = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        errors.append(what)


def read_tum(path):
    """A TUM file's poses as lists of fields (text, so equal means equal to the last digit)."""
    return [line.split() for line in open(path) if line.strip() and not line.startswith("#")]


def check_in_session_frame(work, folder, what):
    """The localized poses in WORK/FOLDER: one for nearly every pose of the mapping run (WORK/run, the
    session's maker, on the same bag) and each within 5 cm of it, in the session's map frame."""
    node = {r[0]: [float(x) for x in r[1:4]] for r in read_tum(f"{work}/{folder}/trajectory.tum")}
    mapped = {r[0]: [float(x) for x in r[1:4]] for r in read_tum(f"{work}/run/trajectory.tum")}
    common = [t for t in node if t in mapped]
    worst = max((math.dist(node[t], mapped[t]) for t in common), default=float("inf"))
    check(len(common) >= 0.9 * len(mapped), f"a localized pose for every mapped one ({len(common)} of {len(mapped)})")
    check(worst < 0.05, f"{what}: within {100 * worst:.2f} cm of the mapping run's poses")


def check_found_in_session(work, folder):
    """WORK/FOLDER's report: localized in the session within 3 s of its first message. Returns its
    `localization` section."""
    loc = json.load(open(f"{work}/{folder}/report.json")).get("localization", {})
    check(loc.get("localized") is True, f"the node localized in the session ({loc.get('last_reason')})")
    check(0 <= loc.get("first_localized_s", -1) < 3, f"within 3 s of its first message ({loc.get('first_localized_s')} s)")
    return loc


def check_driver_restarts(work, folder, ate, run_ate):
    """WORK/FOLDER: a node whose velodyne driver stopped 12 s in for 5 s and whose IMU driver stopped
    22 s in for 2 s, each restarting: one gap each, the status degraded naming both, odometry on
    throughout, ATE (odometry) within 2x mmlio run's (run_ate)."""
    report = json.load(open(f"{work}/{folder}/report.json"))
    velodyne = report["input"]["lidar_streams"]["velodyne"]
    t0 = min(st["first_s"] for st in report["input"]["lidar_streams"].values())
    gaps = [g for g in velodyne["gaps"] if 11.0 < g["after_s"] - t0 < 13.0 and g["missing"] >= 45]
    check(len(gaps) == 1, f"the velodyne's 5 s silence is one gap 12 s in ({velodyne['gaps']})")
    check(report["status"].startswith("degraded") and "velodyne scans missing" in report["status"],
          f"the run is degraded and names the LiDAR ({report['status'][:90]})")
    imu = report["input"]["imu_stream"]
    imu_gaps = [g for g in imu["gaps"] if 21.5 < g["after_s"] - t0 < 22.5 and g["missing"] >= 300]
    check(len(imu_gaps) == 1, f"the IMU's 2 s silence is one gap 22 s in ({imu['gaps']})")
    check("IMU" in report["status"], f"... and the status names it ({report['status'][:160]})")
    odo = read_tum(f"{work}/{folder}/trajectory_odometry.tum")
    def poses(lo, hi):
        return len([p for p in odo if lo < float(p[0]) - t0 < hi])
    check(poses(12.5, 16.5) >= 35, f"odometry goes on while the velodyne is silent ({poses(12.5, 16.5)} poses in 4 s)")
    check(poses(18.0, 21.0) >= 25, f"... and after its driver is back ({poses(18.0, 21.0)} poses in 3 s)")
    check(poses(22.5, 23.5) >= 8, f"... and while the IMU is silent ({poses(22.5, 23.5)} poses in 1 s)")
    # Seconds on one LiDAR, then on the LiDARs alone, cost some accuracy (HI is 2 cm in this office), not the run.
    check(ate <= 2.0 * run_ate, f"ATE {100 * ate:.2f} cm across the restarts, within 2x mmlio run's {100 * run_ate:.2f} cm")


def write_second_pass(work, folder):
    """WORK/FOLDER's odometry from where its stamps went back (the bag played again) on, to
    WORK/FOLDER_second.tum."""
    odo = read_tum(f"{work}/{folder}/trajectory_odometry.tum")
    back = next((i for i in range(1, len(odo)) if float(odo[i][0]) < float(odo[i - 1][0])), len(odo))
    with open(f"{work}/{folder}_second.tum", "w") as out:
        out.write("".join(" ".join(r) + "\n" for r in odo[back:]))


def check_replayed(work, folder, again_ate, run_ate):
    """WORK/FOLDER: a node fed the bag from 5 s in (in motion), then all of it again (its clock 30 s
    back): the forced start and the jump reported, the second pass tracked in the first one's world,
    its odometry ATE (again_ate) within 1.5x mmlio run's (run_ate). write_second_pass first."""
    report = json.load(open(f"{work}/{folder}/report.json"))
    jumps = report["input"]["time_base_jumps"]
    check(report["imu_init"]["forced"] is True,
          f"started in motion: IMU initialised without a standstill ({report['imu_init']['message'][:80]})")
    check(len(jumps) == 1 and -31.0 < jumps[0]["shift_s"] < -29.0, f"one jump of the time base, 30 s back ({jumps})")
    check(report["status"].startswith("degraded") and "time base" in report["status"],
          f"the report says so ({report['status'][:90]})")
    odo = read_tum(f"{work}/{folder}/trajectory_odometry.tum")
    run = read_tum(f"{work}/run/trajectory_odometry.tum")
    second = read_tum(f"{work}/{folder}_second.tum")
    check(len(second) >= 0.95 * len(run), f"the second pass tracked ({len(second)} poses; mmlio run {len(run)})")
    check(report["sweeps"]["coverage"] > 0.95, f"poses cover the stream, both passes ({report['sweeps']['coverage']:.3f})")
    first = {r[0]: [float(x) for x in r[1:4]] for r in odo[: len(odo) - len(second)]}
    t0 = float(read_tum(f"{work}/sim/office_gt.tum")[0][0])  # the bag's start
    def apart(lo, hi):
        return max((math.dist(first[r[0]], [float(x) for x in r[1:4]]) for r in second
                    if r[0] in first and lo <= float(r[0]) - t0 < hi), default=1.0)
    # The first pass's first seconds carry the forced initialisation's error (a few cm), then it settles.
    check(apart(0, 10) < 0.10 and apart(10, 31) < 0.03,
          f"both passes in one world: the second within {100 * apart(0, 10):.2f} cm of the first until 10 s, "
          f"{100 * apart(10, 31):.2f} cm after")
    check(again_ate <= 1.5 * run_ate + 1e-4, f"second pass ATE {100 * again_ate:.2f} cm (mmlio run {100 * run_ate:.2f} cm)")


def finish():
    sys.exit(1 if errors else 0)


if __name__ == "__main__":
    command, work, folder = sys.argv[1:4]
    if command == "second_pass":
        write_second_pass(work, folder)
    else:
        {"driver_restarts": check_driver_restarts, "replayed": check_replayed}[command](
            work, folder, float(sys.argv[4]), float(sys.argv[5]))
    finish()
