#!/usr/bin/python3
"""Turn a recorded ground-truth trajectory into a smooth, level motion for the simulator.

Input: "t x y z qx qy qz qw" per line (TUM; the TIERS dataset's GT_*.csv files, MIT licence).
Ground truths from SLAM + NDT are tilted (their map frame is not level) and jittery at 10 Hz, and
their first samples jump while the matcher converges. This script
  1. drops samples that jump (faster than --max-speed from the previous kept sample),
  2. levels the world: fits a plane to the positions (a ground rig drives on a level floor) and
     rotates it to horizontal, then removes the rig's mean tilt so it rides level on average,
  3. smooths x y z yaw pitch roll with a Gaussian (--sigma seconds) and resamples every --step s,
  4. moves the start to the origin, the path's long axis along x, and writes a C++ table of
     {t_s, x_m, y_m, z_m, yaw_rad, pitch_rad, roll_rad} rows.
Plain Python: no numpy needed.
"""
import argparse
import math


def qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


def qrot(q, v):
    x, y, z, w = qmul(qmul(q, (v[0], v[1], v[2], 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return (x, y, z)


def qconj(q):
    return (-q[0], -q[1], -q[2], q[3])


def qbetween(u, v):
    """The shortest rotation taking unit vector u to unit vector v."""
    c = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    w = 1.0 + sum(a * b for a, b in zip(u, v))
    n = math.sqrt(sum(a * a for a in c) + w * w)
    return (c[0] / n, c[1] / n, c[2] / n, w / n)


def euler_zyx(q):
    x, y, z, w = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return yaw, pitch, roll


def solve3(a, b):
    """Solves the 3x3 system a x = b (Cramer's rule)."""
    def det(m):
        return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
    d = det(a)
    out = []
    for k in range(3):
        m = [row[:] for row in a]
        for i in range(3):
            m[i][k] = b[i]
        out.append(det(m) / d)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("input")
    ap.add_argument("--name", required=True, help="C++ identifier of the table")
    ap.add_argument("--max-speed", type=float, default=2.5, help="m/s; faster steps are dropped as jumps")
    ap.add_argument("--sigma", type=float, default=0.2, help="s, Gaussian smoothing")
    ap.add_argument("--source", default="", help="where the input comes from, and its licence (a comment)")
    ap.add_argument("--step", type=float, default=0.1, help="s, output spacing")
    args = ap.parse_args()

    rows = [list(map(float, line.replace(",", " ").split())) for line in open(args.input) if line.strip()]
    rows.sort(key=lambda r: r[0])
    # 1. Jumps: the first samples (the matcher converging) and single outliers.
    start = 0
    while start + 2 < len(rows):
        d1 = math.dist(rows[start][1:4], rows[start + 1][1:4]) / max(rows[start + 1][0] - rows[start][0], 1e-3)
        if d1 < args.max_speed:
            break
        start += 1
    kept = [rows[start]]
    for r in rows[start + 1:]:
        if math.dist(r[1:4], kept[-1][1:4]) / max(r[0] - kept[-1][0], 1e-3) < args.max_speed:
            kept.append(r)
    dropped = len(rows) - len(kept)

    # 2. Level: the plane z = a x + b y + c through the positions, rotated to horizontal.
    sxx = sxy = sx = syy = sy = sxz = syz = sz = 0.0
    for r in kept:
        x, y, z = r[1:4]
        sxx += x * x; sxy += x * y; sx += x; syy += y * y; sy += y; sxz += x * z; syz += y * z; sz += z
    a, b, _ = solve3([[sxx, sxy, sx], [sxy, syy, sy], [sx, sy, float(len(kept))]], [sxz, syz, sz])
    n = (-a, -b, 1.0)
    nn = math.sqrt(sum(c * c for c in n))
    q_level = qbetween(tuple(c / nn for c in n), (0.0, 0.0, 1.0))
    poses = [(r[0], qrot(q_level, r[1:4]), qmul(q_level, tuple(r[4:8]))) for r in kept]
    # The rig's mean tilt: its mean "up" in its own frame, rotated onto the body z axis.
    up = [0.0, 0.0, 0.0]
    for _, _, q in poses:
        u = qrot(qconj(q), (0.0, 0.0, 1.0))
        up = [s + c for s, c in zip(up, u)]
    un = math.sqrt(sum(c * c for c in up))
    q_fix = qbetween((0.0, 0.0, 1.0), tuple(c / un for c in up))
    poses = [(t, p, qmul(q, q_fix)) for t, p, q in poses]

    # 3. Smooth coordinates (yaw unwrapped) and resample.
    coords = []
    prev_yaw = None
    for t, p, q in poses:
        yaw, pitch, roll = euler_zyx(q)
        if prev_yaw is not None:
            yaw += 2 * math.pi * round((prev_yaw - yaw) / (2 * math.pi))
        prev_yaw = yaw
        coords.append((t, p[0], p[1], p[2], yaw, pitch, roll))
    t0, t1 = coords[0][0], coords[-1][0]
    out = []
    t = t0
    lo = 0
    while t <= t1 + 1e-9:
        while lo < len(coords) and coords[lo][0] < t - 4 * args.sigma:
            lo += 1
        acc = [0.0] * 6
        wsum = 0.0
        i = lo
        while i < len(coords) and coords[i][0] <= t + 4 * args.sigma:
            w = math.exp(-0.5 * ((coords[i][0] - t) / args.sigma) ** 2)
            acc = [s + w * c for s, c in zip(acc, coords[i][1:])]
            wsum += w
            i += 1
        out.append([t - t0] + [s / wsum for s in acc])
        t += args.step

    # 4. Start at the origin; the path's long axis (principal axis of x, y) along +x.
    x0, y0, z0 = out[0][1], out[0][2], out[0][3]
    mx = sum(r[1] for r in out) / len(out)
    my = sum(r[2] for r in out) / len(out)
    cxx = sum((r[1] - mx) ** 2 for r in out)
    cyy = sum((r[2] - my) ** 2 for r in out)
    cxy = sum((r[1] - mx) * (r[2] - my) for r in out)
    yaw0 = 0.5 * math.atan2(2 * cxy, cxx - cyy)
    if math.cos(out[0][4] - yaw0) < 0:  # the walk starts heading into +x
        yaw0 += math.pi
    c, s = math.cos(-yaw0), math.sin(-yaw0)
    print(f"// Generated by scripts/level_recorded_motion.py from {args.input.split('/')[-1]}; do not edit.")
    if args.source:
        print(f"// Source: {args.source}")
    print(f"// ({len(rows)} samples, {dropped} dropped as jumps, level by {math.degrees(math.acos(1 / nn)):.2f} deg,"
          f" sigma {args.sigma} s, step {args.step} s).")
    print(f"// Columns: t_s, x_m, y_m, z_m, yaw_rad, pitch_rad, roll_rad.")
    print(f"constexpr double {args.name}[][7] = {{")
    for r in out:
        dx, dy = r[1] - x0, r[2] - y0
        print("    {%.2f, %.4f, %.4f, %.4f, %.5f, %.5f, %.5f}," % (
            r[0], c * dx - s * dy, s * dx + c * dy, r[3] - z0, r[4] - yaw0, r[5], r[6]))
    print("};")


if __name__ == "__main__":
    main()
