"""The map layer: the arm's modes as functions of its pose, their files and providers.

One wrapping style for both kinds of map. A map is a :class:`~tvist.maps.files.MapDocument`
that holds the Rust core's map (``core``) and its metadata: :class:`DynamicMap` (the
ten-coefficient ``"paper10"`` map, :mod:`tvist.maps.paper10`) and :class:`ModalMap` (the
``"modal"`` map, :mod:`tvist.maps.modal`). Its per-cycle provider for :class:`tvist.TvShaper`
is a subclass of the core's provider built from ``(robot, map)``: :class:`MapDynamics` and
:class:`ModalDynamics`. :func:`load_map` reads a file of either kind (the core's reader,
:mod:`tvist.maps.files`) and :func:`dynamics_for` builds the provider of either kind (both
in :mod:`tvist.maps.dynamics`). :func:`modes_to_shape` and :func:`set_modes_for_move` choose
the modes a move needs shaped (:mod:`tvist.maps.mode_choice`).
"""

from __future__ import annotations

from tvist.maps.dynamics import dynamics_for, load_map
from tvist.maps.modal import ModalDynamics, ModalMap, modal_map_from_flex
from tvist.maps.mode_choice import ModeResidual, ShapingChoice, modes_to_shape, set_modes_for_move
from tvist.maps.paper10 import DynamicMap, MapDynamics, MapRangeWarning

__all__ = [
    "DynamicMap",
    "MapDynamics",
    "MapRangeWarning",
    "ModalDynamics",
    "ModalMap",
    "ModeResidual",
    "ShapingChoice",
    "dynamics_for",
    "load_map",
    "modal_map_from_flex",
    "modes_to_shape",
    "set_modes_for_move",
]
