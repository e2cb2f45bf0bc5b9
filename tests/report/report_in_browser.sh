#!/usr/bin/env bash
# CTest: report.html as a user opens it, in Debian's headless Chromium. A short simulated office
# run with ground truth; the page must draw the 3D map (pixels in the WebGL canvas and in a
# screenshot), hold the plots and the summary's ATE as report.json states it, request nothing
# outside the file (its Content-Security-Policy reports any attempt), and stay small.
# Usage: report_in_browser.sh MMLIO_BINARY WORK_DIR
set -euo pipefail
mmlio="$1"
work="$2/report_in_browser"
browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
  echo "chromium not installed (scripts/install-deps.sh installs it)"
  exit 1
fi
rm -rf "$work"
mkdir -p "$work"
"$mmlio" -q simulate --scenario office --duration 12 --seed 3 --out "$work/sim" > "$work/simulate.log" 2>&1
"$mmlio" -q run "$work/sim/office.bag" --calib "$work/sim/office_truth.yaml" --gt "$work/sim/office_gt.tum" \
  --no-progress --out "$work/run" > /dev/null
page="$work/run/report.html"
flags=(--headless=new --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader --window-size=1280,1600
       --virtual-time-budget=10000 --user-data-dir="$work/profile")
timeout 300 "$browser" "${flags[@]}" --dump-dom "file://$page" > "$work/dom.html" 2> "$work/browser.log"
timeout 300 "$browser" "${flags[@]}" --screenshot="$work/shot.png" "file://$page" >> "$work/browser.log" 2>&1

python3 - "$work" <<'PY'
import json, os, re, struct, sys, zlib
work = sys.argv[1]
dom = open(f"{work}/dom.html", encoding="utf-8").read()
report = json.load(open(f"{work}/run/report.json"))
failures = []
def check(ok, what):
    if not ok:
        failures.append(what)

drawn = re.search(r'id="view3d"[^>]*data-drawn-pixels="(\d+)"', dom)
check(drawn and int(drawn.group(1)) > 20000, f"3D view drew {drawn.group(1) if drawn else 'nothing'} pixels")
check("<canvas" in dom and 'id="view3d-canvas"' in dom, "no WebGL canvas")
check('data-blocked' not in dom, "the page tried to load something outside itself")
check(len(re.findall(r"<svg", dom)) >= 5, "fewer than 5 plots")
for title in ("Top view", "Position error after alignment", "Features per sweep", "Time per stage"):
    check(title in dom, f"plot '{title}' missing")
ate_cm = report["evaluation"]["ate_rmse_m"] * 100
shown = re.search(r'data-figure="ate_cm".*?class="v">([0-9.]+) cm<', dom, re.S)
check(shown and abs(float(shown.group(1)) - ate_cm) <= 0.05 * ate_cm + 0.005,
      f"summary ATE {shown.group(1) if shown else 'missing'} vs report.json {ate_cm:.3f} cm")
check(re.search(r'id="status">complete<', dom) is not None, "status missing")
page = open(f"{work}/run/report.html", encoding="utf-8").read()
check(re.search(r'\s(src|href)\s*=\s*"(?!#|data:)', page) is None, "a src/href points outside the file")
check(os.path.getsize(f"{work}/run/report.html") < 30e6, "report.html over 30 MB")

# The screenshot: decode the PNG (8-bit RGB/RGBA, no interlace) and look at the 3D view's area.
data = open(f"{work}/shot.png", "rb").read()
pos, idat, width = 8, b"", 0
while pos < len(data):
    n, kind = struct.unpack(">I4s", data[pos:pos + 8])
    body = data[pos + 8:pos + 8 + n]
    if kind == b"IHDR":
        width, height, depth, colour = struct.unpack(">IIBB", body[:10])
    elif kind == b"IDAT":
        idat += body
    pos += 12 + n
channels = {2: 3, 6: 4}[colour]
raw, stride = zlib.decompress(idat), width * channels
rows, prev = [], bytearray(stride)
for y in range(height):
    f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
    for i in range(stride):
        a = line[i - channels] if i >= channels else 0
        b, c = prev[i], prev[i - channels] if i >= channels else 0
        p = a + b - c
        pred = {0: 0, 1: a, 2: b, 3: (a + b) // 2,
                4: a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else (b if abs(p - b) <= abs(p - c) else c)}[f]
        line[i] = (line[i] + pred) & 255
    rows.append(line)
    prev = line
colours = set()
for y in range(0, height, 7):
    for x in range(0, width, 7):
        px = rows[y][x * channels:x * channels + 3]
        colours.add(tuple(v // 16 for v in px))
check(len(colours) > 40, f"screenshot nearly blank ({len(colours)} colours)")
if failures:
    print("FAIL:\n  " + "\n  ".join(failures))
    sys.exit(1)
print(f"report.html: 3D view {drawn.group(1)} px, ATE {shown.group(1)} cm (report.json {ate_cm:.3f}), "
      f"{len(colours)} colours in the screenshot, {os.path.getsize(f'{work}/run/report.html') / 1e6:.1f} MB")
PY
