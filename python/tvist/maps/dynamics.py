"""A map of either kind: read from its file (:func:`load_map`, the kind the file names) and
its per-cycle provider (:func:`dynamics_for`)."""

from __future__ import annotations

from pathlib import Path

from tvist import _core
from tvist.maps.files import parse_map_file
from tvist.maps.modal import ModalDynamics, ModalMap
from tvist.maps.paper10 import DynamicMap, MapDynamics
from tvist.robots import Robot

__all__ = ["dynamics_for", "load_map"]


def dynamics_for(
    robot: Robot, dynmap: DynamicMap | ModalMap, *, allow_other_robot: bool = False
) -> MapDynamics | ModalDynamics:
    """The provider of ``dynmap`` on ``robot``: a :class:`~tvist.MapDynamics` for a
    :class:`~tvist.DynamicMap`, a :class:`~tvist.ModalDynamics` for a :class:`~tvist.ModalMap`
    (both evaluated in Rust every cycle, the same protocol for :class:`tvist.TvShaper`).

    For a map read with :func:`tvist.load_map`, whose kind the file decides. Anything other
    than a modal map goes to :class:`~tvist.MapDynamics`, which checks it (``TypeError`` for
    a non-map, ``ValueError`` for a map of another robot unless ``allow_other_robot``).
    """
    if isinstance(dynmap, ModalMap):
        return ModalDynamics(robot, dynmap, allow_other_robot=allow_other_robot)
    return MapDynamics(robot, dynmap, allow_other_robot=allow_other_robot)


def load_map(path: str | Path) -> DynamicMap | ModalMap:
    """The map in ``path``: a :class:`~tvist.DynamicMap` for a ``"paper10"`` file (and files
    written before ``kind`` named the form), a :class:`~tvist.ModalMap` for a ``"modal"`` one.
    :func:`dynamics_for` builds the provider of either."""
    core, metadata = parse_map_file(path)
    if isinstance(core, _core.ModalMap):
        return ModalMap._from_core(core, metadata)
    return DynamicMap._from_core(core, metadata)
