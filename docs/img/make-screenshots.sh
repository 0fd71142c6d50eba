#!/usr/bin/env bash
# Regenerate the screenshots of the real rerun viewer shown in docs/reference/streams.md and the report
# figures shown in docs/reference/reports.md. Docs only (not CI). Needs, once, on Debian:
#   apt-get update && apt-get install -y xvfb mesa-vulkan-drivers
# and the project's venv active (the rerun binary comes with rerun-sdk). Run from the repo root.
set -euo pipefail
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
img=docs/img

shot() {   # shot RRD OUT.png WxH [BLUEPRINT.rbl]: the pointer is parked at the screen's bottom edge
    local w=${3%x*} h=${3#*x}
    xvfb-run -a -s "-screen 0 $((2 * w))x$((4 * h - 40))x24" \
        rerun "$1" ${4:-} --screenshot-to "$work/raw.png" --window-size "$3" > "$work/viewer.log" 2>&1
    python - "$work/raw.png" "$2" 2 <<'PY'
import sys
from PIL import Image
src, dst, shrink = sys.argv[1], sys.argv[2], int(sys.argv[3])
im = Image.open(src).convert("RGB")
im = im.resize((im.width // shrink, im.height // shrink), Image.LANCZOS)
im.quantize(colors=128, method=Image.Quantize.MEDIANCUT).save(dst, optimize=True)
PY
    echo "wrote $2"
}

python -m labkit demo --sessions "$work/s" --no-progress --rerun "save:$work/sweep.rrd" > /dev/null
python -m labkit run rigs/emulated-fig618.toml spin-critical --sessions "$work/s2" --no-progress \
    --rerun "save:$work/spin.rrd" > /dev/null
python -m labkit analyse laser recordings/videos/laser-ellipse-medium.mp4 --json "$work/laser.json" \
    --rerun "save:$work/laser.rrd" > /dev/null
python -m labkit replay recordings/sessions/spin-critical-clean --rerun "save:$work/replay.rrd" > /dev/null
python -m labkit run rigs/emulated-camera.toml cone-sweep --sessions "$work/s3" --no-progress \
    --rerun "save:$work/cone.rrd" > /dev/null
python - "$work/rig.rbl" <<'PY'
import sys
import rerun.blueprint as rrb
from labkit.stream.blueprints import rig_views
rrb.Blueprint(rrb.Vertical(*rig_views(["rotor"], ["balance", "floator_tach"])),
              rrb.TimePanel(timeline="time"), collapse_panels=True).save("labkit-run", sys.argv[1])
PY
shot "$work/sweep.rrd" "$img/live-sweep.png" 1400x900
shot "$work/spin.rrd" "$img/live-spin-critical.png" 1400x900
shot "$work/laser.rrd" "$img/live-laser.png" 1400x800
shot "$work/replay.rrd" "$img/live-rig-over-time.png" 1400x900 "$work/rig.rbl"
shot "$work/cone.rrd" "$img/live-cone-sweep.png" 1400x900

python -m labkit report "$work"/s/*-speed-sweep --out "$work/rep-sweep" > /dev/null
python -m labkit analyse strobe recordings/videos/strobe-medium.mp4 --json "$work/strobe.json" > /dev/null
python -m labkit report "$work/strobe.json" --out "$work/rep-strobe" > /dev/null
python - "$work" "$img" <<'PY'
import sys
from PIL import Image
work, img = sys.argv[1], sys.argv[2]
for src, dst in ((f"{work}/rep-sweep/fig-power-law.png", f"{img}/report-fig525.png"),
                 (f"{work}/rep-strobe/fig-strobe-phase.png", f"{img}/report-strobe-phase.png")):
    im = Image.open(src).convert("RGB")
    im = im.resize((im.width * 2 // 3, im.height * 2 // 3), Image.LANCZOS)
    im.quantize(colors=96).save(dst, optimize=True)
    print("wrote", dst)
PY
