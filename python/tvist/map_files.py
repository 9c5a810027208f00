"""Map files of every kind through one loader: the Rust core reads the file, checks it and
says which form it holds (``"paper10"``: :class:`tvist.DynamicMap`; ``"modal"``:
:class:`tvist.ModalMap`). Python, Rust and C read a file identically."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from tvist import _core

if TYPE_CHECKING:
    from tvist.dynmap import DynamicMap
    from tvist.modal_map import ModalMap

__all__ = ["load_map", "parse_map_file"]


def parse_map_file(path: str | Path) -> tuple[Any, dict[str, Any]]:
    """The core map (``_core.DynamicMap`` or ``_core.ModalMap``, by the file's ``kind``) and
    its metadata; a malformed file raises ValueError naming the file and the field."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not UTF-8 text ({exc})") from None
    try:
        return _core.parse_map(text)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


def load_map(path: str | Path) -> DynamicMap | ModalMap:
    """The map in ``path``: a :class:`~tvist.DynamicMap` for a ``"paper10"`` file (and files
    written before ``kind`` named the form), a :class:`~tvist.ModalMap` for a ``"modal"`` one.
    Either goes to :class:`tvist.MapDynamics`."""
    from tvist.dynmap import DynamicMap
    from tvist.modal_map import ModalMap

    core, metadata = parse_map_file(path)
    if isinstance(core, _core.ModalMap):
        return ModalMap._from_core(core, metadata)
    return DynamicMap._from_core(core, metadata)
