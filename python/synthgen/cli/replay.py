"""``synthgen replay JOURNAL -o DIR``: render a scene's change journal again, in this process;
like ``synthgen render``, it prints and records (meta.json) the replayed scene's objects (its
visible instances, by id, with their labels) and lights."""
from __future__ import annotations

import argparse
import os

from . import Command, register
from .common import add_extension_option, add_render_options, interruptible, overrides, render_and_write, say


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("journal", metavar="JOURNAL", help="a journal (DIR/failed/*.journal of a run, Scene.save_journal)")
    p.add_argument("-o", "--output", metavar="DIR",
                   help="output directory (default: out/<journal file name without extension>)")
    add_render_options(p)
    add_extension_option(p)


def run(args: argparse.Namespace) -> int:
    from ..scene.journal import replay

    scene, settings = interruptible(lambda: replay(args.journal, allow_extensions=args.allow_extensions))
    if settings.pop("labels_only", False):
        say(f"{args.journal}: its last render was of labels only; rendering every channel")
    settings.update(overrides(args))
    out_dir = args.output or os.path.join("out", os.path.splitext(os.path.basename(args.journal))[0])
    # What the replayed scene holds (the journal has no scene file's names): its instances that
    # render (hidden ones, a run's pooled instances, do not) and its lights.
    instances = scene.instances()
    meta = {"source": os.path.abspath(args.journal), "objects": [i for i in instances if i["visible"]],
            "hidden_instances": sum(not i["visible"] for i in instances), "lights": scene.lights()}
    return render_and_write(scene, settings, meta, out_dir, args.journal, expose=True)


register(Command("replay", "render a scene's change journal again",
                 "Replay a change journal (a failed frame's DIR/failed/FRAME.journal, `synthgen run --journal`, "
                 "Scene.save_journal) into a fresh scene and render it with the settings of the last render it "
                 "recorded (bit-identical to that render; --spp etc. override), writing the files of `synthgen "
                 "render`, the image times the render's recorded exposure (a frame's camera, weather and post "
                 "exposure steps). A journal of a scene with C extensions embeds their sources: --allow-extensions "
                 "compiles them.", add_arguments, run, order=32, module=__name__))
