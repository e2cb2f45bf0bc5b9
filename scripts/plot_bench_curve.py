#!/usr/bin/env python3
"""Draws `mmlio bench --curve` as an SVG: resident memory and ms per sweep against bag time.

Usage: scripts/plot_bench_curve.py CURVE.csv OUT.svg [--title TEXT] [--passes N]

Two panels sharing the time axis: resident memory after every sweep (MB), and the sweep loop's
ms per sweep as a 10 s running mean (single sweeps scatter too much to show a trend). With
--passes N (the bench's --replay), the pass boundaries are drawn as thin lines. Standard library
only: the SVG is written by hand, so the script runs wherever Python 3 does.
"""
import argparse
import csv
import sys

WIDTH, HEIGHT = 760, 420
LEFT, RIGHT, TOP, GAP, BOTTOM = 64, 20, 34, 44, 40
PANEL_H = (HEIGHT - TOP - GAP - BOTTOM) // 2
MEAN_WINDOW_S = 10.0


def read_curve(path):
    with open(path, newline="") as f:
        rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
    if not rows:
        sys.exit(f"{path}: no sweeps")
    return rows


def running_mean(times, values, window):
    out, lo, total = [], 0, 0.0
    for hi, v in enumerate(values):
        total += v
        while times[hi] - times[lo] > window:
            total -= values[lo]
            lo += 1
        out.append(total / (hi - lo + 1))
    return out


def nice_step(span, ticks=5):
    raw = span / ticks
    for step in (1, 2, 5, 10, 20, 25, 50, 100, 200, 500, 1000, 2000, 5000):
        if step >= raw:
            return step
    return raw


def panel(svg, top, times, values, t_max, label, unit, colour, passes):
    lo = 0.0
    hi = max(values) * 1.1 or 1.0
    x = lambda t: LEFT + (WIDTH - LEFT - RIGHT) * t / t_max
    y = lambda v: top + PANEL_H - PANEL_H * (v - lo) / (hi - lo)
    svg.append(f'<rect x="{LEFT}" y="{top}" width="{WIDTH - LEFT - RIGHT}" height="{PANEL_H}" '
               'fill="none" stroke="#999"/>')
    step = nice_step(hi - lo)
    v = 0.0
    while v <= hi:
        svg.append(f'<line x1="{LEFT}" x2="{WIDTH - RIGHT}" y1="{y(v):.1f}" y2="{y(v):.1f}" stroke="#eee"/>')
        svg.append(f'<text x="{LEFT - 6}" y="{y(v) + 4:.1f}" text-anchor="end">{v:g}</text>')
        v += step
    for p in range(1, passes):
        px = x(t_max * p / passes)
        svg.append(f'<line x1="{px:.1f}" x2="{px:.1f}" y1="{top}" y2="{top + PANEL_H}" stroke="#ddd" '
                   'stroke-dasharray="3,3"/>')
    points = " ".join(f"{x(t):.1f},{y(v):.1f}" for t, v in zip(times, values))
    svg.append(f'<polyline points="{points}" fill="none" stroke="{colour}" stroke-width="1.5"/>')
    svg.append(f'<text x="{LEFT + 6}" y="{top + 16}" font-weight="bold">{label} ({unit})</text>')


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("curve")
    ap.add_argument("out")
    ap.add_argument("--title", default="mmlio bench: memory and time per sweep")
    ap.add_argument("--passes", type=int, default=1)
    a = ap.parse_args()
    rows = read_curve(a.curve)
    times = [r["bag_s"] for r in rows]
    t_max = max(times[-1], 1e-9)
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" '
           f'viewBox="0 0 {WIDTH} {HEIGHT}" font-family="DejaVu Sans, Arial, sans-serif" font-size="12">',
           f'<rect width="{WIDTH}" height="{HEIGHT}" fill="white"/>',
           f'<text x="{WIDTH / 2}" y="20" text-anchor="middle" font-size="14">{a.title}</text>']
    panel(svg, TOP, times, [r["rss_mb"] for r in rows], t_max, "resident memory", "MB", "#1f77b4", a.passes)
    ms = running_mean(times, [r["sweep_ms"] for r in rows], MEAN_WINDOW_S)
    panel(svg, TOP + PANEL_H + GAP, times, ms, t_max, f"ms per sweep, {MEAN_WINDOW_S:g} s mean", "ms",
          "#d62728", a.passes)
    bottom = TOP + 2 * PANEL_H + GAP
    step = nice_step(t_max, 8)
    t = 0.0
    while t <= t_max:
        px = LEFT + (WIDTH - LEFT - RIGHT) * t / t_max
        svg.append(f'<text x="{px:.1f}" y="{bottom + 16}" text-anchor="middle">{t:g}</text>')
        t += step
    svg.append(f'<text x="{WIDTH / 2}" y="{HEIGHT - 6}" text-anchor="middle">bag time (s)</text>')
    svg.append("</svg>")
    with open(a.out, "w") as f:
        f.write("\n".join(svg) + "\n")


if __name__ == "__main__":
    main()
