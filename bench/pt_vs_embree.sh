#!/usr/bin/env bash
# Speed anchor: synthgen vs Embree's own tutorial path tracer (Debian embree-tools)
# on Embree's Cornell box, 256x256, 64 spp, max path length 8, 2 threads.
# Both are timed as whole processes (load, BVH build, render, write a PPM image), three
# runs each, interleaved, in the same invocation; medians are compared as a ratio.
# Last line: speedup_vs_embree_tutorial=<Embree time / synthgen time>.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PY:-.venv/bin/python}
SIZE=${SIZE:-256}
SPP=${SPP:-64}
LEN=${LEN:-8}
THREADS=${THREADS:-2}
RUNS=${RUNS:-3}
MODELS=/usr/share/doc/embree3/models

if ! command -v pathtracer >/dev/null 2>&1 || [ ! -f "$MODELS/cornell_box.ecs" ]; then
  SUDO=$([ "$(id -u)" = 0 ] || echo sudo)
  $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq embree-tools
fi
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT

now() { date +%s.%N; }
embree_times=(); synthgen_times=(); synthgen_json=""
for i in $(seq "$RUNS"); do
  t0=$(now)
  pathtracer -c "$MODELS/cornell_box.ecs" --size "$SIZE" "$SIZE" --spp "$SPP" \
    --max-path-length "$LEN" --threads "$THREADS" -o "$OUT/embree.ppm" >/dev/null 2>&1
  t1=$(now)
  synthgen_json=$("$PY" bench/embree_cbox.py --size "$SIZE" --spp "$SPP" --max-path-length "$LEN" \
    --threads "$THREADS" --light point -o "$OUT/synthgen.ppm")
  t2=$(now)
  embree_times+=("$(echo "$t1 - $t0" | bc -l)")
  synthgen_times+=("$(echo "$t2 - $t1" | bc -l)")
done
area_json=$("$PY" bench/embree_cbox.py --size "$SIZE" --spp "$SPP" --max-path-length "$LEN" \
  --threads "$THREADS" --light area)

"$PY" - "$OUT" "$synthgen_json" "$area_json" "${embree_times[*]}" "${synthgen_times[*]}" <<'PYEOF'
import json, statistics, sys
import numpy as np
import OpenImageIO as oiio
out, sg_json, area_json, e_times, s_times = sys.argv[1:6]
e = [float(x) for x in e_times.split()]
s = [float(x) for x in s_times.split()]
sg = json.loads(sg_json)
area = json.loads(area_json)
a = oiio.ImageBuf(f"{out}/embree.ppm").get_pixels(oiio.FLOAT)
b = oiio.ImageBuf(f"{out}/synthgen.ppm").get_pixels(oiio.FLOAT)
print("scene: Embree cornell_box.obj + .ecs point light, 256x256, 64 spp, max path length 8, 2 threads")
print("embree_tutorial_times_s=" + ",".join(f"{x:.3f}" for x in e))
print("synthgen_times_s=" + ",".join(f"{x:.3f}" for x in s))
print(f"embree_tutorial_median_s={statistics.median(e):.3f}")
print(f"synthgen_median_s={statistics.median(s):.3f}")
print(f"synthgen_render_only_s={sg['render_s']:.3f}")
print(f"synthgen_rays_per_s={sg['rays_per_s']:.4g}")
print("mean_8bit_rgb_embree=" + ",".join(f"{x:.4f}" for x in a.mean(axis=(0, 1))))
print("mean_8bit_rgb_synthgen=" + ",".join(f"{x:.4f}" for x in b.mean(axis=(0, 1))))
print(f"synthgen_area_light_mis_render_s={area['render_s']:.3f}")
print(f"synthgen_area_light_mis_rays_per_s={area['rays_per_s']:.4g}")
print(f"speedup_vs_embree_tutorial={statistics.median(e) / statistics.median(s):.3f}")
PYEOF
