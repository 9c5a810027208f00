"""The twin's pinned calibration, shared by the tests that check it (the library never
imports this)."""

#: The twin's calibration with 5 kg at 5 cm beyond the flange: (f_n Hz, ζ) of the base and
#: shoulder modes at Q1 and Q3. Pinned to ±1 % so that any change of the plant (stiffness,
#: damping law, inertia data, linearisation) is a deliberate decision that updates these
#: numbers and their reasons; the numbers follow from UR5E_FLEX (sim/flex.py) and the UR5e
#: inertia data:
#:
#: - Q1 base, 7.895 Hz, ζ 0.2526: in the stretched pose the base is decoupled (M[0, 1:] ~ 1e-2
#:   against J_0 = M[0, 0] = 8.94 kg m²) and carries no gravity load, so it is the one-joint
#:   oscillator √(k1 / J_0) = √(22000 / 8.94) = 49.6 rad/s. Its damper is loaded by the
#:   shoulder's gear torque, 106.6 N m (smoothed 101.7 N m): c = 5 (1 + 0.056 · 101.7)² =
#:   224 N m s/rad, ζ = c / (2 √(k1 J_0)) = 224 / 887 = 0.2526 (real UR5e: 0.26).
#: - Q1 shoulder, 7.673 Hz, ζ 0.1356: the shoulder gear at 106.6 N m is stiffened by its cubic
#:   term to 20 435 N m/rad (18 000 unloaded), which with J_1 = 8.35 kg m² alone would ring at
#:   7.87 Hz, ζ 0.146 (damping 60 (1 + 0.01 · 101.7) = 121 N m s/rad); the elbow (and wrist)
#:   compliance in series, coupled through M[1, 2] = 3.97 kg m², lowers it by 2.5 %.
#: - Q3 base, 20.16 Hz, ζ 0.0532: folded, J_0 = 1.12 kg m² alone gives √(22000/1.12) = 22.3 Hz;
#:   the off-plane offsets couple the base to the elbow (M[0, 2] = 0.80 kg m²) and the
#:   elbow's and wrists' compliance lowers the mode by 10 % (23.1 Hz with those joints rigid).
#:   The shoulder's gear torque, and with it the base damping, is small (22 N m: c = 19.9
#:   N m s/rad), hence the low ζ (real UR5e: 0.08).
#: - Q3 shoulder, 19.22 Hz, ζ 0.2154: J_1 = 1.18 kg m² with 18 115 N m/rad gives 19.7 Hz,
#:   ζ 0.24 (70.7 N m s/rad at 22 N m), lowered 2.6 % by the elbow coupling (M[1, 2] = 0.38).
TWIN_CALIBRATION = {
    "Q1": ((7.8954, 0.25257), (7.6734, 0.13558)),
    "Q3": ((20.1607, 0.053166), (19.2199, 0.21536)),
}
