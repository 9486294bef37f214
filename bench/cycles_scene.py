"""Blender-side scene builder: moved to python/synthgen/bench/cycles_scene.py (shared with
``synthgen bench``). This file runs it, so the documented command still works:

    blender -b --factory-startup --python-exit-code 1 -P bench/cycles_scene.py -- scene.json
"""
import os
import runpy

runpy.run_path(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python", "synthgen", "bench",
                            "cycles_scene.py"), run_name="__main__")
