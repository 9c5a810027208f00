"""The seeded family of arm variants (tvist.sim.family).

The true modes are checked against the variant's own nonlinear, time-stepped twin: a free
decay from a broadband kick, identified by a multi-channel matrix pencil that knows nothing of
the eigen-analysis (no mode shapes, no starting frequencies).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tvist.sim import Twin
from tvist.sim.family import (
    DAMPING_RANGE,
    SERVO_RATIO_RANGE,
    SOFTEST_ELBOW_OF_SHOULDER,
    STIFFENING_RANGE,
    STIFFNESS_RANGE,
    WRIST_STIFFNESS_RANGE,
    modes_of,
    nominal_variant,
    sample_variant,
)
from tvist.sim.flex import default_flex

Q1 = np.array([0.0, -np.pi, 0.0, -np.pi / 2, 0.0, 0.0])
Q3 = np.array([np.pi / 2, -np.pi / 2, 5 * np.pi / 6, -np.pi / 2, 0.0, 0.0])
ROBOTS = ("ur5e", "ur10e")
DEVELOPMENT_SEEDS = range(100)


def test_a_seed_always_gives_the_same_arm() -> None:
    for robot in ROBOTS:
        a, b = sample_variant(robot, 17), sample_variant(robot, 17)
        assert a == b and a.flex == b.flex
        assert a != sample_variant(robot, 18)
        modes_a, modes_b = a.true_modes(Q3)[:3], b.true_modes(Q3)[:3]
        for x, y in zip(modes_a, modes_b, strict=True):
            assert x.freq_hz == y.freq_hz and x.zeta == y.zeta
            np.testing.assert_array_equal(x.flange_direction, y.flange_direction)
    # The two robots' families are independent draws, not the same factors twice.
    ur5e, ur10e = sample_variant("ur5e", 17), sample_variant("ur10e", 17)
    assert ur5e.stiffness_factor != ur10e.stiffness_factor


@pytest.mark.parametrize("robot", ROBOTS)
def test_drawn_parameters_stay_in_their_ranges(robot: str) -> None:
    nominal = default_flex(robot)
    softest_elbow = SOFTEST_ELBOW_OF_SHOULDER * nominal.k1_nm_per_rad[1] / nominal.k1_nm_per_rad[2]
    n_beams = 0
    elbow = []
    for seed in DEVELOPMENT_SEEDS:
        v = sample_variant(robot, seed)
        k = np.array(v.stiffness_factor)
        assert np.all((k[[0, 1, 5]] >= STIFFNESS_RANGE[0]) & (k[[0, 1, 5]] <= STIFFNESS_RANGE[1]))
        assert softest_elbow <= k[2] <= 1.0
        lo, hi = WRIST_STIFFNESS_RANGE
        assert np.all((k[3:5] >= lo) & (k[3:5] <= hi))
        for values, (lo, hi) in (
            (v.stiffening, STIFFENING_RANGE),
            (v.servo_ratio, SERVO_RATIO_RANGE),
            (v.damping_factor, DAMPING_RANGE),
        ):
            assert all(lo <= x <= hi for x in values), (seed, values)
        flex = v.flex
        flex.validate(6)
        assert flex.servo_nm_per_rad is not None
        # A stiffer joint than nominal gets a shorter step (see the family's docstring).
        assert v.physics_dt_s <= (0.0005 if k.max() <= 1.0 else 0.00025)
        n_beams += v.beams is not None
        elbow.append(k[2] * nominal.k1_nm_per_rad[2] / nominal.k1_nm_per_rad[1])
    # Half the variants bend (binomial, 100 draws: 0.5 ± 0.05; ±4 sd).
    assert 30 <= n_beams <= 70
    # The elbow spans rigid to softer than the shoulder.
    assert min(elbow) < 1.0 < max(elbow)


@pytest.mark.parametrize("robot", ROBOTS)
def test_every_development_variant_has_plausible_first_modes(robot: str) -> None:
    """With 5 kg 5 cm beyond the flange, the first three modes of every variant at
    Q1 and Q3 are under- but not over-damped (ζ in 0.005-0.9), have a unit flange direction
    and strain-energy shares that sum to 1; and the family spreads (frequencies vary by more
    than ±15 % over the seeds, and some variants have an elbow-dominated mode among the first
    three at Q3)."""
    freqs: dict[str, list[list[float]]] = {"Q1": [], "Q3": []}
    elbow_first_three = 0
    for seed in DEVELOPMENT_SEEDS:
        v = sample_variant(robot, seed)
        twin = v.twin(5.0)
        for name, q in (("Q1", Q1), ("Q3", Q3)):
            modes = modes_of(twin, q)[:3]
            freqs[name].append([m.freq_hz for m in modes])
            for m in modes:
                assert 0.005 < m.zeta < 0.9, (seed, name, m)
                assert m.joint_shares.sum() + m.link_share == pytest.approx(1.0, abs=1e-12)
                assert np.linalg.norm(m.flange_direction) == pytest.approx(1.0, abs=1e-12)
            if name == "Q3":
                elbow_first_three += any(int(np.argmax(m.joint_shares)) == 2 for m in modes)
    for name in freqs:
        f = np.array(freqs[name])
        assert np.all(np.diff(f, axis=1) >= 0.0)
        assert np.all(f[:, 0] > 1.0)
        spread = f.max(axis=0) / f.min(axis=0)
        assert np.all(spread > 1.3), (name, spread)
    assert elbow_first_three >= 10


def matrix_pencil_modes(y: np.ndarray, dt_s: float, order: int, window: int) -> np.ndarray:
    """Continuous-time poles (rad/s, positive imaginary part) of a multi-channel free decay
    ``y`` ``(n_samples, n_channels)``: the shift invariance of the stacked Hankel matrices'
    leading ``order`` right singular vectors (Hua and Sarkar's matrix pencil)."""
    hankel = np.vstack(
        [np.lib.stride_tricks.sliding_window_view(y[:, c], window + 1) for c in range(y.shape[1])]
    )
    _, _, vh = np.linalg.svd(hankel, full_matrices=False)
    v = vh[:order].T
    z = np.linalg.eigvals(np.linalg.pinv(v[:-1]) @ v[1:]).astype(complex)
    poles = np.log(z) / dt_s
    return poles[poles.imag > 0.0]


@pytest.mark.slow
@pytest.mark.parametrize(("robot", "seed"), [("ur5e", 0), ("ur10e", 1)])
def test_true_modes_agree_with_a_free_decay_of_the_variants_twin(robot: str, seed: int) -> None:
    """Kicked at rest (0.002 rad/s on every joint, signs mixed: about 2e-5 rad, the linear
    regime), motors held, the variant's twin rings; a matrix pencil on the six joint angles
    (1.5 s sampled at 1 kHz, all ``2 n_state`` poles) finds each of the first three true
    modes at Q1 and Q3.

    On noise-free samples the pencil is not limited by the FFT's 1/T resolution (0.7 Hz here:
    it separates seed 0's 7.24 and 7.31 Hz pair at Q1); what remains is the twin's own time
    step (semi-implicit Euler with trapezoidal damping: a shift of order (ω dt)² and ζ ω dt,
    ≤ 0.2 % at 60 Hz with 0.25 ms) and the nonlinearity at 2e-5 rad (~1e-5). Tolerances
    0.4 % in frequency and 0.005 in ζ (observed at most 0.13 % and 0.001).

    The flange direction: the recorded flange position (MuJoCo's kinematics of the simulated
    state, not the Jacobian the eigen-analysis uses) fitted by least squares on the pencil's
    poles gives each mode's complex flange motion; its major axis is the true mode's direction
    to |cos| > 0.999 (observed >= 0.99993).
    """
    variant = sample_variant(robot, seed)
    twin = variant.twin(5.0)
    dt_s = 0.001
    kick = np.array([1.0, -1.0, 1.0, 1.0, -1.0, 1.0]) * 2e-3
    t_s = np.arange(1500) * dt_s
    for q in (Q1, Q3):
        record = twin.run(np.tile(q, (1500, 1)), dt_s, initial_qd_rad_s=kick)
        y = record.actual_q - twin.equilibrium(q)
        poles = matrix_pencil_modes(y, dt_s, order=2 * twin.n_state, window=300)
        wn = np.abs(poles)
        zeta = -poles.real / wn
        basis = np.column_stack(
            [np.exp(np.outer(t_s, np.concatenate([poles, poles.conj()]))), np.ones(len(t_s))]
        )
        flange, *_ = np.linalg.lstsq(basis, record.actual_TCP_pose[:, :3] + 0j, rcond=None)
        for mode in variant.true_modes(q)[:3]:
            distance = np.abs(wn / (2 * np.pi * mode.freq_hz) - 1.0) + np.abs(zeta - mode.zeta)
            k = int(np.argmin(distance))
            assert wn[k] / (2 * np.pi) == pytest.approx(mode.freq_hz, rel=0.004), (q, mode)
            assert zeta[k] == pytest.approx(mode.zeta, abs=0.005), (q, mode)
            axes, _, _ = np.linalg.svd(np.column_stack([flange[k].real, flange[k].imag]))
            assert abs(axes[:, 0] @ mode.flange_direction) > 0.999, (q, mode)


@pytest.mark.parametrize("robot", ROBOTS)
def test_nominal_variant_is_the_default_twin(robot: str) -> None:
    """Every factor 1 and an ideal servo rebuilds the default gear laws (``k3`` from the rated
    torque the nominal laws imply) and so the default twin's modes. The published ``k3`` are
    rounded to three digits; ``3 k3 δ²`` is at most a quarter of the stiffness at the gravity
    loads, so the frequencies agree to ~1e-4 (observed ~1e-6)."""
    variant = nominal_variant(robot)
    nominal = default_flex(robot)
    np.testing.assert_allclose(variant.flex.k3_nm_per_rad3, nominal.k3_nm_per_rad3, rtol=5e-3)
    assert variant.flex.servo_nm_per_rad is None
    assert dataclasses.replace(variant.flex, k3_nm_per_rad3=nominal.k3_nm_per_rad3) == nominal
    twin = Twin(robot, payload_kg=5.0)
    for q in (Q1, Q3):
        ours = variant.true_modes(q)
        reference = twin.modal_analysis(q)
        n = len(reference.wn_rad_s)
        assert len(ours) == n
        np.testing.assert_allclose([m.freq_hz for m in ours], reference.freq_hz, rtol=1e-4)
        np.testing.assert_allclose([m.zeta for m in ours], reference.zeta, rtol=1e-3)


def test_servo_in_series_softens_the_joint_as_two_springs_do() -> None:
    """With a servo ``k_s`` in series, the spring law is the series combination: the joint
    deflection for a torque is the gear's plus ``τ / k_s``, and the tangent stiffness is
    ``1 / (1/k_gear' + 1/k_s)`` (checked against a central difference of the torque law)."""
    flex = dataclasses.replace(default_flex("ur5e"), servo_nm_per_rad=(4e4,) * 6)
    gear_only = default_flex("ur5e")
    tau = np.array([80.0, -120.0, 40.0, 20.0, -10.0, 2.0])
    delta = flex.deflection_rad(tau)
    np.testing.assert_allclose(delta, gear_only.deflection_rad(tau) + tau / 4e4, rtol=1e-12)
    np.testing.assert_allclose(flex.spring_torque_nm(delta), tau, rtol=1e-10)
    h = 1e-7
    numeric = (flex.spring_torque_nm(delta + h) - flex.spring_torque_nm(delta - h)) / (2 * h)
    np.testing.assert_allclose(flex.tangent_stiffness_nm_per_rad(delta), numeric, rtol=1e-6)
    gear_k = gear_only.tangent_stiffness_nm_per_rad(gear_only.deflection_rad(tau))
    np.testing.assert_allclose(
        flex.tangent_stiffness_nm_per_rad(delta), 1.0 / (1.0 / gear_k + 1.0 / 4e4), rtol=1e-10
    )


@pytest.mark.slow
def test_family_variant_from_the_cli(tmp_path, capsys) -> None:
    """``tvist campaign --sim --variant family:ur5e:3``: the records' true modes are that
    variant's; a malformed family name or another robot is one line naming the flag."""
    from tvist.cli import main
    from tvist.ident.results_store import load_results

    out = tmp_path / "family.jsonl"
    args = ["campaign", "--sim", "--out", str(out), "--payloads", "5", "--duration", "1"]
    args += ["--no-workspace-cover"]
    assert main([*args, "--variant", "family:ur5e:3", "--every", "52"]) == 0
    records = load_results(out)
    assert records
    twin = sample_variant("ur5e", 3).twin(5.0, records[0]["payload_com_m"])
    for record in records:
        # The records list every true mode below 60 Hz; those the twin names base (joint 0)
        # and shoulder (joint 1) are its two modes.
        want = twin.modes(np.array(record["q"]))
        named = {m["joint"]: m for m in record["true_modes"] if m["joint"] is not None}
        got = [(named[j]["wn_rad_s"], named[j]["zeta"]) for j in (0, 1)]
        np.testing.assert_allclose(got, want, rtol=1e-9)
        assert len(record["true_modes"]) >= 2
    capsys.readouterr()
    for extra, message in (
        (["--variant", "family:ur5e:x"], "--variant: twin variant 'family:ur5e:x'"),
        (["--variant", "family:ur3e:1", "--robot", "ur3e"], "defined for ur5e, ur10e"),
        (["--variant", "family:ur10e:1"], "add --robot ur10e"),
    ):
        assert main([*args, *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0], err


def test_the_modal_map_prior_of_a_servo_joint_is_its_series_stiffness() -> None:
    """``modal_map_from_flex`` with a servo: ``k_e + q L²`` is the series joint's tangent
    stiffness at the deflection carrying the load ``L`` (from the exact spring law), to the
    order it neglects: the next term is ``O(L⁴)``, ~1e-4 relative at 30 N m here."""
    from tvist.maps.modal import modal_map_from_flex

    servo = (4e4, 3e4, 2e5, 3e4, 3e4, 4e3)
    flex = dataclasses.replace(default_flex("ur5e"), servo_nm_per_rad=servo)
    entries = modal_map_from_flex(flex).flex_joints
    for entry in entries:
        j = entry["joint"]
        k_e, _, quad = entry["stiffness_nm_per_rad"]
        for load in (0.0, 30.0):
            tau = np.zeros(6)
            tau[j] = load
            exact = flex.tangent_stiffness_nm_per_rad(flex.deflection_rad(tau))[j]
            assert k_e + quad * load**2 == pytest.approx(exact, rel=2e-4), (j, load)
