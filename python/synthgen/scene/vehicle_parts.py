"""What a library vehicle's entry may name (assets_manifest, ``synthgen.scene.assets``) and how
``synthgen.scene.vehicles`` builds it: the roles of a model's materials and the kinds of lamps.
A module of constants below both, so that the manifest's checks and the vehicle builder share
them without importing each other."""
from __future__ import annotations

from typing import Any, Dict

__all__ = ["LAMP_KINDS", "ROLES"]

#: Lamp kinds: the end they are at (+1 front, -1 rear), their default size (width, height in
#: metres), the colour of the unlit lens (linear RGB albedo) and of the light (linear RGB, its
#: luminance normalised to 1). Their luminance when lit is the ``lamps`` randomizer's.
LAMP_KINDS: Dict[str, Dict[str, Any]] = {
    "head": {"end": 1.0, "size": (0.22, 0.10), "lens": (0.55, 0.55, 0.55), "light": (1.0, 0.97, 0.9)},
    "tail": {"end": -1.0, "size": (0.16, 0.08), "lens": (0.22, 0.012, 0.01), "light": (1.0, 0.02, 0.005)},
    "brake": {"end": -1.0, "size": (0.12, 0.06), "lens": (0.22, 0.012, 0.01), "light": (1.0, 0.02, 0.005)},
    "indicator_front": {"end": 1.0, "size": (0.07, 0.05), "lens": (0.5, 0.22, 0.02), "light": (1.0, 0.42, 0.0)},
    "indicator_rear": {"end": -1.0, "size": (0.07, 0.05), "lens": (0.5, 0.22, 0.02), "light": (1.0, 0.42, 0.0)},
}

#: Roles a library entry can give a model's materials.
ROLES = ("paint", "glass", "chrome", "rubber", "trim")
