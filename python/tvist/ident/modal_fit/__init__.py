"""Fit a :class:`tvist.ModalMap` to the base and shoulder modes identified at many poses, each
named by its excitation joint (the label-based fit; ``tvist fit-map --kind modal
--select-folds K``, the demo's modal rows). ``tvist fit-map --kind modal`` fits every
identified mode instead, each matched to the model's eigenmode it is
(:mod:`tvist.ident.all_modes_fit`).

The same pose records as :func:`tvist.ident.map_fit.fit_map` (the campaign's JSON lines) are
used, plus each pose's configuration ``q`` and payload, from which the robot model gives the
mass matrix and the gravity torques. Two steps give the start, like the published map's fit:

1. **Stiffness** (nonlinear least squares on relative frequency errors) of the undamped map
   (no damping: the undamped modes). Per flexible joint ``k(L) = k_0 (1 + a_1 |L|_s + a_2 L²)``
   with ``L`` its gravity torque; the parameters are ``log k_0`` and ``a_1, a_2 >= 0`` (the
   load terms only for joints whose gravity torque varies over the poses).
2. **Damping** with the stiffness fixed. For light damping the damping ratio is nearly
   *linear* in the damping laws' coefficients (exactly so for the damping projected on the
   undamped modes, ``ζ = (ω/2) Σ_j (v_j²/k_j)(c_0 + c_1 |L|_s + c_2 L²)``), so it is a
   non-negative linear least-squares problem on relative errors; its columns are evaluations
   of the core map with one unit coefficient each (the physics stays in one place, the
   Rust core).

A term whose estimate is below ``drop_t`` standard errors is dropped and the step refitted.

3. **Joint refinement** (default): every kept stiffness and damping coefficient together, robust
   least squares on the relative errors of ω and ζ, each in units of its scatter (the records'
   stated standard errors weigh the poses, the residuals set each quantity's scale), from the
   two-step solution. The prediction is the core map's, the exact damped modes: their natural
   frequencies depend on the damping where modes with different damping come close (the
   UR5e's base and shoulder at folded poses), so steps 1 and 2 are only a start.

Standard errors are ``√diag(σ² (JᵀJ)⁻¹)`` at the solution (through the SVD of ``J``, residuals
beyond ``OUTLIER_SIGMAS`` robust standard deviations left out), in physical units.

:func:`select_terms` (``select_folds``) chooses the stiffness model by held-out frequency error
instead of significance alone.

:func:`cross_validate` compares this form with the published 10-coefficient form on held-out
poses (k-fold over poses), against the identified modes and, for a twin's campaign, against
the true modes.

Modules, by stage: ``poses`` (the records read: :func:`modal_poses`), ``model`` (law terms
and the core map's prediction), ``two_stage`` (steps 1 and 2), ``refinement`` (step 3),
``statistics`` (standard errors, coefficient table, relative errors), ``fit``
(:func:`fit_modal_map`, the stages in order), ``selection`` (:func:`select_terms`) and
``cross_validation`` (:func:`cross_validate`). ``python -m tvist.cli.modal_fit`` prints the
cross-validation.
"""

from __future__ import annotations

from tvist.ident.modal_fit.cross_validation import cross_validate
from tvist.ident.modal_fit.fit import fit_modal_map
from tvist.ident.modal_fit.model import DEFAULT_FLEX_JOINTS
from tvist.ident.modal_fit.poses import ModalPoses, modal_poses
from tvist.ident.modal_fit.selection import held_out_frequency_error, select_terms
from tvist.ident.modal_fit.statistics import relative_errors

__all__ = [
    "DEFAULT_FLEX_JOINTS",
    "ModalPoses",
    "cross_validate",
    "fit_modal_map",
    "held_out_frequency_error",
    "modal_poses",
    "relative_errors",
    "select_terms",
]
