"""Object randomizers: what a scenario can do to each object beyond its shape and
material -- road signs, licence plates, decals, wear.

A randomizer owns one key of a scenario's ``objects[]`` entries (its schema, every leaf a
distribution) and, per object and frame, changes the object: its material (wrapped in wear,
layered with decals, generated for a sign or a plate), and for the randomizers that *are*
the object (``sign``, ``plate``) its shape, size and mounting post. What it did goes into the
frame's metadata under its key.

Protocol (:class:`Randomizer`):

- ``key``, ``schema`` -- the scenario key and its schema;
- ``sample_order`` -- the key's position in ``objects[]`` (distributions are drawn in this
  order) and in the metadata; ``apply_order`` -- the order in which randomizers change an
  object's material (a plate or sign first, decals before wear);
- ``shape``: for randomizers that are the object (one of ``primitive`` / ``mesh`` /
  ``asset`` / ...): :meth:`Randomizer.make_shape` and :meth:`Randomizer.placement`;
- :meth:`Randomizer.needs` -- why the randomizer cannot change an object of a model
  (:class:`ModelParts`: the material roles, plate mounts and lamps it offers), or None; the run
  refuses such an object (:meth:`Randomizer.refuse`, in ``apply``) and ``synthgen validate``
  asks it of every model an entry can draw;
- :meth:`Randomizer.apply` -- returns the object's new materials and its metadata record.
  An object has one material, or -- a model with materials of its own -- one per material
  of its mesh; a randomizer that wraps materials (wear, decals) wraps each, so the model
  keeps them (the frame gives the instance a per-instance material map).

Adding a randomizer is one module here (found by :func:`discover`, registered with
:func:`register`) plus its test; the scenario schema, the order of application and the
docs follow from the registry.
"""
from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass
from typing import Any, Dict, FrozenSet, List, Mapping, Optional, Tuple

import numpy as np

from .._core import SynthgenError
from ..schema.fields import Field

__all__ = ["Randomizer", "ObjectContext", "ModelParts", "register", "randomizers", "randomizer", "discover",
           "randomizer_modules", "INFRASTRUCTURE"]


@dataclass
class ObjectContext:
    """What a randomizer may use while it changes one object of one frame."""

    scene: Any                    #: the frame's scene facade (records per-frame textures / materials)
    rng: np.random.Generator      #: the object's generator: a pure function of (seed, frame, object)
    spec: Any                     #: the sampled object (synthgen.scenario.ObjectSpec)
    shape_lo: np.ndarray          #: object-space bounds of the object's shape
    shape_hi: np.ndarray
    #: The shape's forward and up directions in its object space (unit axes; declared by the
    #: asset or objects[].forward/up, else +x and +y): where its front is and which way is up.
    forward: Tuple[float, float, float] = (1.0, 0.0, 0.0)
    up: Tuple[float, float, float] = (0.0, 1.0, 0.0)
    #: A vehicle's plate mounts (name -> 4 x 3 corners in object space) and the placeholder
    #: material of each one's quad (None: the model has no plate mounts).
    plates: Optional[Dict[str, np.ndarray]] = None
    plate_material: Optional[Dict[str, int]] = None
    #: A vehicle's lamps (name -> {kind, side, centre, corners, normal} in object space) and
    #: the placeholder material of each lens (None: the model declares no lamps).
    lamps: Optional[Dict[str, Dict[str, Any]]] = None
    lamp_material: Optional[Dict[str, int]] = None
    #: The model's material ids by the role its library entry gives them ({"paint": [...]}).
    roles: Optional[Dict[str, List[int]]] = None


@dataclass(frozen=True)
class ModelParts:
    """What an object's model offers the randomizers that change parts of it: the roles of the
    materials the object keeps (its library entry's ``materials``: none when the model is no
    library vehicle or the object's ``material`` replaces its own), and whether its entry
    declares plate mounts and lamps. The run reads them from the frame's shape
    (:meth:`of_context`), ``synthgen validate`` from the asset's manifest entry and its
    material names (:meth:`of_entry`), so both refuse the same objects."""

    roles: FrozenSet[str] = frozenset()
    plates: bool = False
    lamps: bool = False

    @classmethod
    def of_context(cls, ctx: ObjectContext, materials: List[int]) -> "ModelParts":
        keep = set(materials)
        return cls(frozenset(r for r, ids in (ctx.roles or {}).items() if keep & set(ids)),
                   bool(ctx.plates) and ctx.plate_material is not None,
                   bool(ctx.lamps) and ctx.lamp_material is not None)

    @classmethod
    def of_entry(cls, entry: Mapping[str, Any], roles: Mapping[str, List[int]], replaced: bool) -> "ModelParts":
        """``roles``: synthgen.scene.vehicles.material_roles of the model; ``replaced``: the
        object's ``material`` replaces the model's own."""
        return cls(frozenset() if replaced else frozenset(r for r, ids in roles.items() if ids),
                   bool(entry.get("plates")), bool(entry.get("lamps")))


class Randomizer:
    """Base class of the object randomizers (see the module docstring)."""

    key: str = ""
    schema: Field
    sample_order: int = 0
    apply_order: int = 0
    #: True for randomizers that are the object itself (a sign, a plate): they make its shape.
    shape: bool = False

    def make_shape(self, scene: Any) -> Tuple[int, np.ndarray, np.ndarray]:
        """(mesh id, object-space lo, hi) of the object's mesh (``shape`` randomizers; the
        mesh is made once per worker and shared by every object of this randomizer)."""
        raise NotImplementedError

    def placement(self, value: Mapping[str, Any], scale: float) -> Tuple[np.ndarray, float, np.ndarray, float]:
        """(object_from_shape 4x4, footprint radius, box dimensions, post height) of an object
        (``shape`` randomizers): a post from the ground up to that height (behind the panel,
        up to its middle, so the panel sits on it at any size and shape)."""
        raise NotImplementedError

    def needs(self, parts: ModelParts) -> Optional[str]:
        """Why this randomizer cannot change an object whose model offers ``parts`` (None: it
        can; the default: any model)."""
        return None

    def refuse(self, ctx: ObjectContext, materials: List[int]) -> None:
        """SynthgenError ``objects[i].<key>: <reason>`` when :meth:`needs` refuses the object."""
        why = self.needs(ModelParts.of_context(ctx, materials))
        if why:
            raise SynthgenError(f"objects[{ctx.spec.index}].{self.key}: {why}")

    def apply(self, ctx: ObjectContext, value: Any, materials: List[int]) -> Tuple[List[int], Any]:
        """Changes the object: ``materials`` are its material ids (one, or one per material of
        its mesh; empty for a ``shape`` randomizer, which makes the object's material);
        returns the new ones (same length; a ``shape`` randomizer returns one) and what to
        record in the metadata under :attr:`key` (None: nothing)."""
        raise NotImplementedError


_REGISTRY: Dict[str, Randomizer] = {}

#: Modules of this package that are not randomizers.
INFRASTRUCTURE: Tuple[str, ...] = ("weather",)  # weather: the frame's conditions, a package of its own


def register(r: Randomizer) -> Randomizer:
    """Adds a randomizer (called by its module at import)."""
    if not r.key or r.key in _REGISTRY:
        raise SynthgenError(f"randomizer {r.key!r} has no key or is registered twice")
    _REGISTRY[r.key] = r
    return r


def randomizers(by: str = "sample_order") -> List[Randomizer]:
    """Every randomizer, by ``sample_order`` (schema and metadata order) or ``apply_order``."""
    return sorted(_REGISTRY.values(), key=lambda r: getattr(r, by))


def randomizer(key: str) -> Randomizer:
    return _REGISTRY[key]


def randomizer_modules() -> List[str]:
    return sorted(m.name for m in pkgutil.iter_modules(__path__) if m.name not in INFRASTRUCTURE)


def discover() -> None:
    """Imports every randomizer module, which registers its randomizer."""
    for name in randomizer_modules():
        importlib.import_module(f"{__name__}.{name}")


discover()
