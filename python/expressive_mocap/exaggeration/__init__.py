"""Expressive features for movement exaggeration (Davis & Kannappan, "Expressive Features for
Movement Exaggeration", SIGGRAPH 2002 sketch).

From performances of one action at known intensities (e.g. walks 'exhausted' < 'normal' <
'active' as 1 < 2 < 3), find the joint-angle trajectories (DOFs) that change most and most
predictably with intensity (the *key features*), model their change, and exaggerate or diminish
a new motion of the same action.

Pipeline and shapes (``T`` samples a cycle, ``D`` DOFs, ``K`` intensities, ``P`` people,
``r`` basis vectors), and the module of each step:

1. :mod:`.cycles`: a cycle (footstrike to next footstrike of the same foot, or a whole clip)
   resampled to ``T`` samples (slerp / linear) with the heading removed (the hips pre-multiplied
   by the inverse yaw of the cycle's travel direction);
2. :mod:`.dofs`: DOFs ``[T, D]``: per joint the rotation vector of ``m_j^-1 q_j`` (``m_j`` the
   joint's mean over the person's samples, one hemisphere), 3 a joint, plus the hips height /
   actor height (``D = 3 J + 1``); Euler channels relative to the mean as an option;
3. :mod:`.fitting`: ``A [T, P K D]``, thin SVD, ``U [T, r]`` keeping 99% of ``sum(s^2)``;
   coefficients ``U^T x``;
4. observability ``O_d = ||c_d(k_1) - c_d(k_K)|| w_j`` (``w_j`` the summed bone lengths below
   joint ``j``), predictability ``P_d = sum_i s_i / sum(s) |rho(c_{d,i}(k), k)|``,
   ``E_d = O_d P_d^2``, normalised and accumulated to ``share`` (0.9): key features.
   By default (``cycle="all"``) a performance is the mean of every cycle of its clip (in DOF
   space) and ``rho`` is taken over every cycle, each at its clip's intensity. With one sample
   per intensity (the paper's single cycle; ``cycle="middle"``) three points decide ``rho``, and for
   three points the correlation of pure noise follows the arcsine law (median ``|rho|`` 0.71), so
   a DOF that only varies scores almost as predictable as one that follows the intensity; over
   every cycle (about 20 a person on the Bandai walks) ``rho`` also sees the step-to-step spread;
5. least-squares lines ``c_{d,i}(k)``, averaged over people (:mod:`.training` runs 1-5 on clips
   into an :class:`ExaggerationModel`, :mod:`.model`);
6. :mod:`.estimate`: a new motion's current intensity ``k0`` (given, or estimated by least
   squares over the key DOFs' mapped coefficients weighted by how well the mapping predicts each,
   from how each DOF varies over the cycle around the motion's own mean pose, so an actor's own
   posture does not move it, optionally after a baseline clip of the actor at a known intensity
   has taken out the actor's difference; with an uncertainty and a fit residual:
   :meth:`ExaggerationModel.estimate`);
7. :mod:`.edit`: per cycle: ``x' = x + U (f(k1) - f(k0))`` on the key DOFs, mapped back onto each
   cycle's own frames, cross-faded at cycle boundaries, clamped to the training range plus a
   margin, optionally with the stance foot locked (:mod:`.footlock`);
8. :mod:`.timing`: each cycle's duration and the hips' travel over it (logs), mapped by intensity
   like the coefficients; the edit retimes the cycles and scales the travel by what the mappings
   say (for the features that follow the intensity), and foot locking holds the feet at the new
   timing.

:mod:`.validation` holds the paper's swap test and the leave-one-person-out warp, :mod:`.plot`
the ranking's table and figure, :mod:`.settings` every default.
"""

from __future__ import annotations

from .cycles import Cycle, cycle_heading, find_cycles, normalise_cycle, to_cycle_timing
from .dofs import dof_names, dofs_to_rotations, rotations_to_dofs, subtree_weights
from .edit import ExaggerationReport, exaggerate, stance_foot_speed
from .estimate import IntensityEstimate
from .fitting import FitResult, fit
from .footlock import lock_stance_feet
from .model import ExaggerationModel
from .settings import EDITING, TRAINING, VALIDATION, EditSettings, TrainSettings, ValidationSettings
from .timing import Timing
from .training import train
from .validation import (
    RankAgreement,
    SwapResult,
    TimedResult,
    WarpResult,
    dof_positions,
    leave_one_out,
    rank_agreement,
    swap_test,
    timing_validation,
    validation_table,
)

__all__ = [
    "EDITING",
    "TRAINING",
    "VALIDATION",
    "Cycle",
    "EditSettings",
    "ExaggerationModel",
    "ExaggerationReport",
    "FitResult",
    "IntensityEstimate",
    "RankAgreement",
    "SwapResult",
    "TimedResult",
    "Timing",
    "TrainSettings",
    "ValidationSettings",
    "WarpResult",
    "cycle_heading",
    "dof_names",
    "dof_positions",
    "dofs_to_rotations",
    "exaggerate",
    "find_cycles",
    "fit",
    "leave_one_out",
    "lock_stance_feet",
    "normalise_cycle",
    "rank_agreement",
    "rotations_to_dofs",
    "stance_foot_speed",
    "subtree_weights",
    "swap_test",
    "timing_validation",
    "to_cycle_timing",
    "train",
    "validation_table",
]
