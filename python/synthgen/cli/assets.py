"""``synthgen assets list|fetch``: the assets of the manifest."""
from __future__ import annotations

import argparse

from . import Command, register


def _list(args: argparse.Namespace) -> int:
    from ..scene import assets

    print("\n".join(assets.list_assets()))
    return 0


def _fetch(args: argparse.Namespace) -> int:
    from ..scene import assets

    for i, p in assets.fetch(args.ids or None).items():
        print(f"{i}: {p}")
    return 0


def add_arguments(p: argparse.ArgumentParser) -> None:
    asub = p.add_subparsers(dest="assets_command", metavar="ACTION", required=True)
    q = asub.add_parser("list", help="list asset ids")
    q.set_defaults(func=_list)
    q = asub.add_parser("fetch", help="fetch assets (default: all) into the cache")
    q.add_argument("ids", nargs="*", metavar="ID")
    q.set_defaults(func=_fetch)


register(Command("assets", "list or fetch assets of the manifest",
                 "List the assets of assets_manifest/*.yaml, or fetch them into the cache ($SYNTHGEN_CACHE or "
                 "~/.cache/synthgen), verifying checksums.", add_arguments, None, order=60, module=__name__))
