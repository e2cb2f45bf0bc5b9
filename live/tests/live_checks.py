"""What the live node tests' checks share: every check printed, the run failed at the end if any did."""
import sys

errors = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        errors.append(what)


def read_tum(path):
    """A TUM file's poses as lists of fields (text, so equal means equal to the last digit)."""
    return [line.split() for line in open(path) if line.strip() and not line.startswith("#")]


def finish():
    sys.exit(1 if errors else 0)
