"""Material slots across frames: an object index that held a textured scenario material last
frame and holds a library vehicle (its own materials) this frame, when an entry's count
changes, lets go of last frame's texture before that texture is removed. Before the fix such
frames failed with "texture N is still used by material M"."""
import json
import os

from synthgen import run as runner

from test_output_kitti import _asset

CAR = "mesh/sumo-car-normal-citrus"


def test_a_vehicle_taking_a_textured_boxs_index_renders(tmp_path):
    _asset(CAR)
    scen = tmp_path / "s.yaml"
    scen.write_text(f"""
seed: 2
count: 6
resolution: [64, 48]
camera: {{fov_y: 50, pose: {{type: orbit, target: [0, 0.5, 0], distance: 12, elevation: 15, azimuth: 270}}}}
lights: [{{type: sky, strength: 0.02}}]
objects:
  - {{class: car, asset: {CAR}, count: {{choice: [0, 1]}}, region: [-1, -1, 1, 1]}}
  - {{label: false, primitive: box, count: 2, size: [0.5, 1, 1], region: [4, -4, 6, 4],
     material: {{type: diffuse, albedo: {{texture: {{type: noise, scale: 3}}}}}}}}
placement: {{region: [-6, -6, 6, 6], min_pixels: 0, min_visible_fraction: 0}}
render: {{spp: 1, max_depth: 1}}
outputs: [rgb]
""")
    out = str(tmp_path / "ds")
    s = runner.run(str(scen), out, count=6, progress=False, workers=1)
    assert not s["failures"], s.text()
    counts = [json.load(open(os.path.join(out, "meta", f"{k:06d}.json")))["sampled"]["objects[0].count"]["choice"]
              for k in range(6)]
    # The case itself: a frame without the car (the box at index 0) followed by one with it.
    assert any(a == 0 and b == 1 for a, b in zip(counts, counts[1:])), counts
