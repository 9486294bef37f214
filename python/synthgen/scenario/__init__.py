"""Scenarios: randomized scenes -> one frame's parameters at a time.

A scenario is a YAML mapping (``scenarios/default.yaml`` is a complete example)::

    version: 1
    seed: 7                       # frame k's randomness derives only from (seed, k)
    count: 100                    # frames (``synthgen run -n`` overrides)
    resolution: [640, 480]
    camera:
      fov_y: {uniform: [40, 55]}  # degrees; or intrinsics fx, fy (cx, cy: image centre)
      pose: {type: orbit, target: [0, 0.4, 0], distance: {uniform: [5, 8]},
             elevation: {uniform: [10, 35]}, azimuth: {uniform: [0, 360]}, jitter: 0.2}
    lights:                       # a list, or {choice: [list, list, ...]} of light set-ups
      - {type: sky, elevation: {uniform: [15, 70]}, azimuth: {uniform: [0, 360]}, strength: 0.02}
    ground: {size: 40, material: {type: diffuse, albedo: [0.3, 0.3, 0.3]}}
    objects:
      - class: box                # class name: COCO category / YOLO index / KITTI type
        count: {int: [1, 3]}
        primitive: box            # box | sphere, or mesh: FILE / asset: ID / sign / plate
        size: {uniform: [[0.3, 0.3, 0.3], [1, 1, 1]]}
        yaw: {uniform: [0, 360]}
        material: {type: coated, albedo: {hsv: {color: [0.6, 0.1, 0.1], h: 0.5, s: 0.3, v: 0.3}}}
    placement: {region: [-3, -3, 3, 3], non_overlapping: true, min_visible_fraction: 0.1}
    render: {spp: 32, max_depth: 6}
    outputs: [rgb, depth, instance, semantic, coco, yolo, kitti]

Every value may be a distribution (:mod:`synthgen.schema.distributions`). Modules:
:mod:`.schema` (the format, generated from the plugin declarations and the randomizer and
output registries), :mod:`.load` (validation into a :class:`Scenario`), :mod:`.sample`
(one frame's typed records from (seed, frame) only), :mod:`.inputs` (every input file loaded
once, constant materials and lights created, before anything renders).
"""
from .inputs import check_inputs  # noqa: F401
from .load import Scenario, load_scenario, parse_scenario  # noqa: F401
from .sample import (CameraSpec, FrameSpec, GroundSpec, ObjectSpec, PluginSpec, frame_rng,  # noqa: F401
                     sample_frame)
from .schema import SCENARIO_SCHEMA  # noqa: F401
