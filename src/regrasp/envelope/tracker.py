r"""Following one finger's ``urdf`` envelope from one control step to the next (issue 6).

A regrasp supervisor evaluates every finger's feasible envelope at every control step (1 kHz),
while the object moves by about :math:`10^{-4}` m per step. :meth:`FingerEnvelope.at
<regrasp.envelope.finger_envelope.FingerEnvelope.at>` in the ``urdf`` geometry finds its collision cuts from
scratch: a grid of 33 points per piece of reachable ∩ edge plus the ``ideal`` ends, then a
bisection of every flip of coal's verdict. :class:`EnvelopeTracker` holds the last sample's
*cuts* (per piece of reachable ∩ edge: the verdict at its start and the free side of every flip)
and re-locates each cut near where it was:

1. the closed-form part (line, condition, reachable set, reachable ∩ edge) is computed exactly as
   :meth:`~regrasp.envelope.finger_envelope.FingerEnvelope.at` does, by the envelope's
   :class:`~regrasp.envelope.evaluator.EnvelopeEvaluator` (the ``ideal`` feasible set only on a fallback);
2. if the *structure* is unchanged — the same condition, the same number of reachable pieces, of
   pieces of reachable ∩ edge and of tip positions inside each where link 1 passes through a vertex
   (the ``ideal`` set's only cuts), and coal's verdict at both ends of every piece and at its
   ``WATCHED`` interior grid points of ``at`` nearest to a change is what it was — each cut is
   searched from its extrapolated position :math:`e + \dot e\,\Delta t` by steps of
   :math:`\tau, 2\tau, 4\tau, \dots` (:math:`\tau` the bisection tolerance of ``at``) until the
   verdict flips, and the last step is bisected to :math:`\tau`. When the prediction is within
   :math:`\tau` this costs two collision queries per cut. The queries use collision certificates
   that outlive the object pose
   (:meth:`~regrasp.model.collision.UrdfCollisionChecker.links_collide_kept`), so coal runs mostly at
   the cuts. On the compiled path
   (:attr:`FingerEnvelope.compiled <regrasp.envelope.finger_envelope.FingerEnvelope.compiled>`) each query is one
   closed-form kernel call instead, and a fallback takes ``at``'s cuts from the same kernel
   (:meth:`~regrasp.envelope.finger_envelope.FingerEnvelope.urdf_cuts`);
3. it falls back to the full ``at`` computation when anything is ambiguous: the first call, a pose
   jump above ``max_pose_step``, any change of the structure, a search that leaves the piece or
   goes farther than one grid step of ``at``, or two cuts closer than one grid step of ``at`` plus
   :math:`2\tau` (a set about to split or join, where ``at``'s grid may see a different number of
   pieces).

What a fallback returns is bitwise what ``at`` returns. What a tracked update returns has the same
pieces as ``at``, each cut on the free side of the same flip within :math:`\tau` (both searches
end on the free side of a bracket no wider than :math:`\tau`), provided coal's verdict on ``at``'s
grid has no flips other than the tracked ones. The checks above catch a flip that appears at a
piece's end, where link 1 passes a vertex, or at a watched grid point; a collision island born
elsewhere inside a piece is not looked for. On random fingers (thick distal links grazing the
edge) this misses a few such births for a few steps, so the supervisor uses the tracker only when
asked (``SupervisorSettings.track_envelopes``). Tests compare tracked and fresh samples at every
step along the three-finger paper trajectory and on random pose sequences around it.
"""

from __future__ import annotations

import math
import time as _time
from collections import Counter
from typing import NamedTuple

from numpy.typing import ArrayLike

from ..core.exceptions import InvalidParameterError
from ..core.intervals import Intervals
from ..core.validation import as_positive_float
from .evaluator import FreeTest, UrdfCuts, urdf_pieces
from .finger_envelope import EnvelopeSample, FingerEnvelope
from .floats import pose_floats

__all__ = ["EnvelopeTracker"]

#: Count key of an update that needed no collision query (``ideal`` geometry, or no piece of
#: reachable ∩ edge).
CLOSED_FORM = "closed form"
#: How many interior grid points of ``at`` the tracker watches per piece of reachable ∩ edge.
WATCHED = 2
#: Count key of an update whose cuts were followed from the previous one.
TRACKED = "tracked"
#: Count key of an update on a curved object: always :meth:`FingerEnvelope.at` (no cuts are followed on a curve),
#: with the previous foot as ``near`` so that ξ stays unwrapped.
CURVE = "curve"


class _Cuts(NamedTuple):
    """What the tracker holds between updates (line coordinates s [m], see ``FingerEnvelope``)."""

    pose: tuple[float, float, float, float]  # (x [m], y [m], cos beta, sin beta) of the object
    time: float  # [s]
    structure: tuple  # (condition, reachable pieces, per piece of reachable ∩ edge: vertex cuts inside)
    ends: UrdfCuts  # per piece of reachable ∩ edge: (free at its start, free sides of the flips)
    rates: tuple  # per piece, per flip: the cut's rate [m/s] at the last update (0 when unknown)
    kept: tuple  # per piece: collision certificates at its start, at its end and at each cut


def _locate(free: FreeTest, kept: list, guess: float, left: bool, lo: float, hi: float, tol: float, reach: float,
            known: tuple[bool, bool]) -> float | None:
    """The free side of the one flip of ``free`` near ``guess`` in (lo, hi) [m]: ``free`` is ``left``
    just below the flip. Steps of tol, 2 tol, 4 tol… [m] from ``guess`` until the verdict flips,
    then bisection to ``tol``; ``kept``: the collision certificates of this cut (``free``'s second
    argument). ``known``: whether ``free(lo) == left`` and ``free(hi) != left``
    are known to hold (the first and the last flip of a piece), so that lo or hi can close the
    bracket. None when a step would leave (lo, hi) otherwise, or go farther than ``reach`` [m]
    from ``guess``."""
    if not lo < guess < hi:
        return None
    a = b = guess
    step = tol
    if free(guess, kept) == left:  # the flip is above
        while True:
            b = a + step
            if b - guess > reach:
                return None
            if b >= hi:
                if not known[1]:
                    return None
                b = hi
                break
            if free(b, kept) != left:
                break
            a, step = b, 2.0 * step
    else:  # the flip is below
        while True:
            a = b - step
            if guess - a > reach:
                return None
            if a <= lo:
                if not known[0]:
                    return None
                a = lo
                break
            if free(a, kept) == left:
                break
            b, step = a, 2.0 * step
    while b - a > tol:
        m = 0.5 * (a + b)
        if free(m, kept) == left:
            a = m
        else:
            b = m
    return a if left else b


class EnvelopeTracker:
    r"""One finger's envelope, updated from one control step to the next (module docstring).

    Args:
        envelope: The finger's envelope on its edge. In the ``ideal`` geometry every update is
            :meth:`~regrasp.envelope.finger_envelope.FingerEnvelope.at` (closed form: nothing to follow).
        max_pose_step: An update whose object pose moved by more than this since the last one
            (:math:`|\Delta x_o| + R\,|\Delta(\cos\beta, \sin\beta)|`, R the object's largest
            vertex radius: the largest displacement of a point of the object)
            is computed from scratch [m].

    Attributes:
        last: The last sample (None before the first update or after :meth:`reset`).
        counts: How each update was made: ``"tracked"``, ``"closed form"``, ``"curve"`` (a curved object's
            envelope: always :meth:`~regrasp.envelope.finger_envelope.FingerEnvelope.at`), or the reason of a
            fallback to the full computation (``"first call"``, ``"pose jump"``, ``"structure"``,
            ``"piece end"``, ``"birth"`` (a watched grid point changed), ``"lost a cut"``,
            ``"narrow piece"``).
    """

    def __init__(self, envelope: FingerEnvelope, *, max_pose_step: float = 1e-3):
        if not isinstance(envelope, FingerEnvelope):
            raise InvalidParameterError("envelope", envelope, "a FingerEnvelope")
        self.envelope = envelope
        self.max_pose_step = as_positive_float("max_pose_step", max_pose_step)
        if envelope.curved:  # (every update is at(): nothing below is used)
            self._radius, self._tol = 0.0, envelope.urdf_tolerance * envelope.edge.period
        else:
            self._radius = max(math.hypot(vx, vy) for vx, vy in envelope.polygon.vertices.tolist())
            self._tol = envelope.urdf_tolerance * envelope.edge.length
        self.last: EnvelopeSample | None = None
        self.counts: Counter[str] = Counter()
        self._cuts: _Cuts | None = None

    def reset(self) -> None:
        """Forget the last sample: the next update is computed from scratch."""
        self.last = None
        self._cuts = None

    @property
    def fallbacks(self) -> int:
        """How many updates fell back to the full computation (``counts`` less tracked and closed form)."""
        return sum(n for key, n in self.counts.items() if key not in (TRACKED, CLOSED_FORM))

    def update(self, pose_object_in_hand: ArrayLike, time: float = 0.0) -> EnvelopeSample:
        """The envelope at the object pose ``(x [m], y [m], beta [rad])`` in the hand frame at ``time`` [s]."""
        t_start = _time.perf_counter()
        env = self.envelope
        evaluator = env.evaluator
        x, y, beta = pose_floats(pose_object_in_hand)
        time = float(time)
        if not math.isfinite(time):
            raise InvalidParameterError("time", time, "a finite number [s]")
        if env.curved:
            self.counts[CURVE] += 1
            self.last = env.at((x, y, beta), time, near=None if self.last is None else self.last.xi_foot)
            return self.last
        if env.checker is None:
            frame = evaluator.closed_form(x, y, beta)
        else:  # the ideal feasible set only if it falls back (its ends are at()'s extra grid points)
            frame = evaluator.closed_form(x, y, beta, ideal=False)
        if env.checker is None or not frame.base:
            self.counts[CLOSED_FORM] += 1
            self._cuts = None
            self.last = env.sample(frame, frame.ideal, time, t_start)
            return self.last
        d, nx, ny = frame.d, frame.nx, frame.ny
        # where link 1 passes through a vertex: the ideal set's only cuts, and where the urdf cuts
        # of link 1 are born and die
        _, vertex_cuts = evaluator.vertex_cuts(x, y, frame.c, frame.s, d, nx, ny)
        structure = (frame.condition, len(frame.reach),
                     tuple(sum(lo < t < hi for t in vertex_cuts) for lo, hi in frame.base))
        free = evaluator.free_test(x, y, beta, d, nx, ny)
        cuts = self._cuts
        if cuts is None:
            outcome = "first call"
        elif (math.hypot(x - cuts.pose[0], y - cuts.pose[1])
              + self._radius * math.hypot(frame.c - cuts.pose[2], frame.s - cuts.pose[3]) > self.max_pose_step):
            outcome = "pose jump"
        elif structure != cuts.structure:
            outcome = "structure"
        else:
            outcome = self._follow(cuts, frame.base, free, time)
        if isinstance(outcome, str):
            self.counts[outcome] += 1
            if env.compiled:  # at()'s own cuts, from the same kernel call
                ends = env.urdf_cuts((x, y, beta))
            else:
                ideal = evaluator.ideal_feasible(frame.base, x, y, frame.c, frame.s, d, nx, ny)
                ends = evaluator.urdf_ends(frame.base, ideal, free)
            rates = tuple((0.0,) * len(flips) for _, flips in ends)
            kept = tuple(self._sites(lo, hi, flips, free) for (lo, hi), (_, flips) in zip(frame.base, ends))
        else:
            self.counts[TRACKED] += 1
            ends, rates, kept = outcome
        self._cuts = _Cuts((x, y, frame.c, frame.s), time, structure, ends, rates, kept)
        self.last = env.sample(frame, urdf_pieces(frame.base, ends), time, t_start)
        return self.last

    def _sites(self, lo: float, hi: float, flips: tuple, free: FreeTest) -> tuple:
        """The collision certificates of a piece [lo, hi] of reachable ∩ edge (line coordinates [m]) with
        cuts ``flips``: at its start, at its end, at each cut, and the watched points of ``at``'s grid
        (grid index, verdict, certificates): the ``WATCHED`` interior grid points farther than 1.5
        grid steps from every cut and end whose verdict is the nearest to changing (smallest
        signed-distance magnitude)."""
        grid = self.envelope.urdf_grid - 1
        step = (hi - lo) / grid
        ends = (lo, *flips, hi)
        candidates = []
        for j in range(1, grid):
            s = j * step + lo  # at()'s grid point j
            if min(abs(s - e) for e in ends) < 1.5 * step:
                continue
            kept = [None, None]
            verdict = free(s, kept)
            candidates.append((min(abs(c[-1]) for c in kept if c is not None), j, verdict, kept))
        candidates.sort(key=lambda c: c[0])
        watched = tuple((j, verdict, kept) for _, j, verdict, kept in candidates[:WATCHED])
        return [None, None], [None, None], tuple([None, None] for _ in flips), watched

    def _follow(self, cuts: _Cuts, base: Intervals, free: FreeTest, time: float) -> tuple[UrdfCuts, tuple, tuple] | str:
        """(ends, rates, certificates) with every cut of ``cuts`` re-located on ``base`` (line
        coordinates [m]), or the reason to compute the sample from scratch."""
        tol = self._tol
        dt = time - cuts.time
        grid = self.envelope.urdf_grid - 1
        new_ends, new_rates = [], []
        for (lo, hi), (start_free, flips), rates, (at_lo, at_hi, at_flips, watched) in zip(
                base, cuts.ends, cuts.rates, cuts.kept):
            if free(lo, at_lo) != start_free or free(hi, at_hi) != (start_free != (len(flips) % 2 == 1)):
                return "piece end"
            step = (hi - lo) / grid  # at()'s grid step on this piece
            for j, verdict, kept in watched:
                if free(j * step + lo, kept) != verdict:
                    return "birth"
            left = start_free
            found = []
            last = len(flips) - 1
            for j, (e, rate, kept) in enumerate(zip(flips, rates, at_flips)):
                at = _locate(free, kept, e + rate * dt if dt > 0.0 else e, left, lo, hi, tol, step + 2.0 * tol,
                             (j == 0, j == last))
                if at is None:
                    return "lost a cut"
                found.append(at)
                left = not left
            if any(b - a < step + 2.0 * tol for a, b in zip(found, found[1:])):
                return "narrow piece"
            new_ends.append((start_free, tuple(found)))
            new_rates.append(tuple((b - a) / dt if dt > 0.0 else 0.0 for a, b in zip(flips, found)))
        return tuple(new_ends), tuple(new_rates), cuts.kept
