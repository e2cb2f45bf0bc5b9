"""What the live node tests' checks share: every check printed, the run failed at the end if any did."""
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


def finish():
    sys.exit(1 if errors else 0)
