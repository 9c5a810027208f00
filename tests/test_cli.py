"""The command line: every subcommand is registered and ``--method`` selects demo rows."""

from __future__ import annotations

import pytest

from tvist.cli import _demo_row_method, build_parser
from tvist.demo import default_methods


def test_every_command_parses_its_help():
    parser = build_parser()
    for name in ("demo", "zero-delay", "campaign", "identify", "fit-map", "sensitivity", "shape"):
        with pytest.raises(SystemExit) as exit_:
            parser.parse_args([name, "--help"])
        assert exit_.value.code == 0


def test_demo_rows_belong_to_the_methods_a_user_can_choose():
    kinds = {m.key: _demo_row_method(m.key) for m in default_methods()}
    assert kinds["unshaped"] == "unshaped"
    assert {kinds[k] for k in kinds if k != "unshaped"} == {"tvist", "ztdis", "mztdis"}
    assert _demo_row_method("fd-tvist-identified-map") == "tvist"
    with pytest.raises(SystemExit):
        build_parser().parse_args(["demo", "--method", "bogus"])


def test_subpackages_load_on_first_access_without_heavy_imports():
    import subprocess
    import sys

    code = (
        "import sys, tvist\n"
        "assert 'mujoco' not in sys.modules and 'matplotlib' not in sys.modules\n"
        "assert callable(tvist.trajectory.double_s) and callable(tvist.ident.read_rtde_csv)\n"
        "assert tvist.sim.Twin and callable(tvist.analysis.residual_vibration)\n"
        "assert 'mujoco' not in sys.modules  # the simulator loads only with a Twin\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
    with pytest.raises(AttributeError, match="no attribute"):
        import tvist

        _ = tvist.not_a_subpackage
