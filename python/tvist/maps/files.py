"""Map files of every kind through one reader: the Rust core reads the file, checks it and
says which form it holds (``"paper10"``: :class:`tvist.DynamicMap`; ``"modal"``:
:class:`tvist.ModalMap`; :func:`tvist.maps.dynamics.load_map` wraps it as one or the other).
Python, Rust and C read a file identically."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar, TypeVar

from tvist import _core
from tvist.robots import Payload

__all__ = ["MapDocument", "RobotModesMixin", "parse_map_file"]

_Map = TypeVar("_Map", bound="MapDocument")


def plain_metadata(metadata: Mapping[str, Any] | None) -> dict[str, Any] | None:
    """``metadata`` with a :class:`~tvist.robots.Payload` written as its dict."""
    if metadata is None:
        return None
    if not isinstance(metadata, Mapping):
        raise ValueError("metadata: must be an object")
    out = dict(metadata)
    if isinstance(out.get("payload"), Payload):
        out["payload"] = out["payload"].to_dict()
    return out


class MapDocument:
    """What every map kind shares: the core map it wraps, its metadata and its file.

    A subclass names its core type (``_core_type``) and the message for a file of the other
    kind (``_other_kind``).
    """

    _core_type: ClassVar[type]
    _other_kind: ClassVar[str]
    _core: Any
    metadata: dict[str, Any]

    @classmethod
    def _from_core(cls: type[_Map], core: Any, metadata: dict[str, Any]) -> _Map:
        if not isinstance(core, cls._core_type):
            raise ValueError(cls._other_kind)
        out = cls.__new__(cls)
        out._core, out.metadata = core, metadata
        return out

    @property
    def n_modes(self) -> int:
        """Number of modes (shaper filters in cascade)."""
        return self._core.n_modes

    @property
    def uses_gravity(self) -> bool:
        """True if the map reads gravity torques."""
        return self._core.uses_gravity

    def to_dict(self) -> dict[str, Any]:
        """The JSON document of this map (as the core writes it)."""
        return _core.map_document(self._core, plain_metadata(self.metadata))

    def to_json(self) -> str:
        """The map file's text: strict JSON (no NaN or Infinity)."""
        return _core.write_map(self._core, plain_metadata(self.metadata))

    def save(self, path: str | Path) -> None:
        """Write the map file."""
        Path(path).write_text(self.to_json(), encoding="utf-8")

    @classmethod
    def from_dict(cls: type[_Map], doc: Any) -> _Map:
        """Validate and build from a parsed map document."""
        return cls._from_core(*_core.map_from_document(doc))

    @classmethod
    def load(cls: type[_Map], path: str | Path) -> _Map:
        """Read and validate a map file of this kind; malformed files raise ValueError naming
        the file and the field (overflowing numbers, NaN tokens and deep nesting included). A
        file of the other kind is refused (:func:`tvist.load_map` reads either kind)."""
        core, metadata = parse_map_file(path)
        try:
            return cls._from_core(core, metadata)
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None


class RobotModesMixin:
    """What the two robot-driven providers share (``tvist.MapDynamics`` with a
    :class:`~tvist.DynamicMap`, ``tvist.ModalDynamics`` with a :class:`~tvist.ModalMap`):
    the argument checks, the Python objects they keep and their repr."""

    robot: Any
    dynmap: Any

    @staticmethod
    def _check(robot: Any, law: Any, law_type: type, what: str) -> None:
        from tvist.robots import Robot

        if not isinstance(robot, Robot):
            raise TypeError(f"robot must be a tvist.robots.Robot, got {type(robot).__name__}")
        if not isinstance(law, law_type):
            raise TypeError(f"{what} must be a tvist.{law_type.__name__}, got {type(law).__name__}")

    def __init__(self, robot: Any, dynmap: Any, *, allow_other_robot: bool = False) -> None:
        self.robot = robot
        self.dynmap = dynmap

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.robot!r}, {self.dynmap!r})"


def parse_map_file(path: str | Path) -> tuple[Any, dict[str, Any]]:
    """The core map (``_core.DynamicMap`` or ``_core.ModalMap``, by the file's ``kind``) and
    its metadata, read by the core (as from C and Rust). A file that is not a valid map (not
    UTF-8, not strict JSON, a repeated key, more than ``_core.MAX_MODES`` modes, a mode that is
    not physical, longer than ``_core.MAX_MAP_FILE_BYTES``) raises ValueError naming the file
    and the field."""
    return _core.load_map_file(path)
