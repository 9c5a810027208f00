"""Map files through ``tvist.load_map`` (the core's one reader, as from C and Rust): physical
rules, the shared mode limit, the size limit, repeated keys and a byte-order mark."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

import tvist

#: Random poses of the UR5e with 5 kg (seeded): where ``.modes()`` of a loaded map is read.
ROBOT = tvist.robots.ur5e(5.0, (0.0, 0.0, 0.05))
POSES = np.random.default_rng(3).uniform(-np.pi, np.pi, size=(200, 6))


def _paper_doc() -> dict:
    return tvist.DynamicMap.paper_ur5e().to_dict()


def _save(tmp_path: Path, doc: dict | str, name: str = "map.json") -> Path:
    path = tmp_path / name
    path.write_text(doc if isinstance(doc, str) else json.dumps(doc, indent=1), encoding="utf-8")
    return path


def _unphysical_modes(doc: dict) -> int:
    """How many (pose, mode) pairs of ``doc``'s modes, evaluated by the core's equations without
    the map's rules, are not a finite ω_n > 0 with ζ >= 0 at :data:`POSES`."""
    inertia = np.array([ROBOT.joint_inertia(q) for q in POSES])
    tau = np.array([ROBOT.gravity_torque(q) for q in POSES])
    bad = 0
    for mode in doc["modes"]:
        wn, zeta = tvist._core.evaluate_trial_mode(mode, inertia, tau)
        bad += int(np.count_nonzero(~(np.isfinite(wn) & (wn > 0) & (zeta >= 0))))
    return bad


@pytest.mark.parametrize(
    ("mode", "key", "value", "message"),
    [
        (0, "k_0", -1e4, r"modes\[0\]: the stiffness k_0 \+ k_j J_f must be > 0"),
        (1, "c_0", -5.0, r"modes\[1\]: the damping c_0 \+ c_1 √J_d \+ c_2 J_d must be >= 0"),
        (1, "k_p", -1.73, r"modes\[1\]: the gain 1 \+ k_p/J_f must be > 0"),
        (0, "k_g", -200.0, r"modes\[0\]: k_g = -200 must be >= 0"),
        (1, "c_tau", -47.2, r"modes\[1\]: the torque factor 1 \+ c_tau J_d must be >= 0"),
    ],
)
def test_a_physically_invalid_map_file_is_refused_at_load(tmp_path, mode, key, value, message):
    doc = _paper_doc()
    doc["modes"][mode][key] = value
    # What loading it used to hand out: modes with NaN or ζ < 0 at poses the arm reaches.
    assert _unphysical_modes(doc) > 0
    path = _save(tmp_path, doc)
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))}: {message}"):
        tvist.load_map(path)
    # The same rule for a map built in Python (one rule, in the core).
    with pytest.raises(ValueError, match=message):
        tvist.DynamicMap(doc["modes"])


def test_every_loadable_map_gives_physical_modes(tmp_path):
    """The paper's map, a fitted-looking ranged map with coefficients that are negative but
    physical inside the range, and its modes at every pose: finite ω_n > 0, ζ >= 0."""
    doc = _paper_doc()
    doc["modes"][1].update(
        k_j=-100.0,  # K = 1e4 − 100 J_1 > 0 for J_1 < 100 kg m²
        c_0=-0.05,  # c_0 + c_2 J_1 >= 0 for J_1 >= 1.3 kg m²
        frequency_inertia_range_kg_m2=[1.5, 12.0],
        damping_inertia_range_kg_m2=[1.5, 12.0],
    )
    loaded = tvist.load_map(_save(tmp_path, doc))
    assert _unphysical_modes(doc) == 0
    modes = np.array([loaded.modes(ROBOT, q) for q in POSES])
    assert np.all(np.isfinite(modes)) and np.all(modes[..., 0] > 0) and np.all(modes[..., 1] >= 0)


def _doc_with_modes(n: int) -> dict:
    doc = _paper_doc()
    doc["modes"] = [doc["modes"][k % 2] for k in range(n)]
    return doc


def test_the_mode_limit_is_one_for_map_files_python_and_the_shaper(tmp_path):
    limit = tvist.MAX_MODES
    assert limit == tvist._core.MAX_MODES == 64
    assert tvist.load_map(_save(tmp_path, _doc_with_modes(limit))).n_modes == limit
    # 2000 modes fit in 1 MiB of compact JSON; 10,000 do not (the size limit refuses them).
    for n in (limit + 1, 2000):
        path = _save(tmp_path, json.dumps(_doc_with_modes(n)))
        with pytest.raises(ValueError, match=rf"modes: the map has {n} modes, more than the limit"):
            tvist.load_map(path)
    with pytest.raises(ValueError, match="is more than the 1 MiB"):
        tvist.load_map(_save(tmp_path, json.dumps(_doc_with_modes(10_000))))
    with pytest.raises(ValueError, match="65 modes, more than the limit of 64"):
        tvist.ConstantModes([(60.0, 0.05)] * (limit + 1))
    # A callable provider reports its count only by its answer: refused by the shaper.
    with pytest.raises(ValueError, match="65 modes, more than the limit of 64"):
        tvist.TvShaper(lambda q: [(60.0, 0.05)] * (limit + 1), dt_s=0.002, n_dof=1, max_delay_s=0.1)
    shaper = tvist.TvShaper(tvist.ConstantModes([(60.0, 0.05)] * limit), dt_s=0.002, n_dof=1)
    assert shaper.n_modes == limit


def test_a_file_longer_than_the_limit_is_refused(tmp_path):
    limit = tvist.MAX_MAP_FILE_BYTES
    assert limit == 2**20
    text = tvist.DynamicMap.paper_ur5e().to_json()
    at_limit = _save(tmp_path, text + " " * (limit - len(text)), "at_limit.json")
    assert tvist.load_map(at_limit).n_modes == 2
    beyond = _save(tmp_path, text + " " * (limit + 1 - len(text)), "beyond.json")
    with pytest.raises(ValueError, match=rf"{limit + 1} bytes is more than the 1 MiB"):
        tvist.load_map(beyond)


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs /dev/zero")
def test_an_endless_device_is_refused_without_reading_it_whole():
    with pytest.raises(ValueError, match=r"/dev/zero: its content is more than the 1 MiB"):
        tvist.load_map("/dev/zero")


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ('"k_0": 10000.0', '"k_0": 10000.0, "k_0": -1.0', "k_0"),
        ('"robot": "ur5e"', '"robot": "ur5e", "robot": "ur10e"', "robot"),
    ],
)
def test_a_repeated_key_is_refused_naming_it(tmp_path, old, new, key):
    text = tvist.DynamicMap.paper_ur5e().to_json()
    doubled = text.replace(old, new, 1)
    assert doubled != text
    with pytest.raises(ValueError, match=rf'the key "{key}" appears twice'):
        tvist.load_map(_save(tmp_path, doubled))


def test_a_byte_order_mark_is_accepted(tmp_path):
    paper = tvist.DynamicMap.paper_ur5e()
    path = tmp_path / "bom.json"
    path.write_text(paper.to_json(), encoding="utf-8-sig")
    assert path.read_bytes()[:3] == b"\xef\xbb\xbf"
    loaded = tvist.load_map(path)
    assert loaded.mode_maps == paper.mode_maps and loaded.metadata == paper.metadata


def test_a_missing_file_names_it(tmp_path):
    missing = tmp_path / "no_such_map.json"
    with pytest.raises(ValueError, match=rf"{re.escape(str(missing))}: cannot read"):
        tvist.load_map(missing)
