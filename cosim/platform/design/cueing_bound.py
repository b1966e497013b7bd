"""The least perceived error any cueing could reach on a drive: how far a cueing is from the best
the platform allows, and whether a goal is within reach at all.

Every cueing, classical, model-predictive or one not yet written, moves the platform within its
stroke and joints, and tilts it no faster than its tilt rate limit (beyond the vehicle's own roll
and pitch rate). Knowing the whole drive ahead, the best motion within those limits is a convex
problem in the cueing MPC's own model (`fmu/cueing/mpc.c`): the six DOFs double integrators from
rest at neutral, the specific force linearised (a_x - g pitch, a_y + g roll, a_z), the perception
the project's measure itself (`cosim.platform.perception`: the same organs, discretised the same
way, the indifference thresholds' dead zone), its objective the perceived error (per channel the
rms of the felt error, in thresholds, summed: a sum of norms, a second-order cone program).

It is relaxed so that its optimum is a floor under every cueing in that model: each DOF may reach
the largest excursion any pose within the legs' stroke and the joints' angle allows it (the others
free; their limits left out, not their margins added), the legs' speeds are free, and the roll and
pitch rates are bounded each alone (the MPC bounds them together). No cueing that keeps the
platform within those limits, whatever it knows ahead, feels closer than this by the measure; the
classical washout's and the MPC's co-simulated errors lie above it (tests/platform/test_cueing_bound.py).

Solved by Clarabel (Goulart and Chen 2024), an interior-point conic solver, on the drive's samples;
the floor is its dual objective (under every feasible point of the program, by weak duality), the
motion it finds felt as far from the vehicle to the solver's tolerance. About 0.2 s per second of
drive on this machine.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..core import Core
from ..perception import CHANNELS, ORGANS, THRESHOLDS, Vestibular, perceive, perceived_error, quality, vehicle_motion

# the DOFs (x, y, z, roll, pitch, yaw) felt in each channel, as the MPC's linearised model has them:
# (channel, translation DOF or None, tilt DOF or None, the tilt's weight in it in g) per sub-problem;
# the angular channels take the rate of the DOF that turns about their axis
SURGE = ((0, 0, 4, -1.0), (4, None, 4, None))    # specific force x = a_x - g pitch; angular rate y = pitch'
SWAY = ((1, 1, 3, 1.0), (3, None, 3, None))     # specific force y = a_y + g roll;  angular rate x = roll'
HEAVE = ((2, 2, None, None),)                    # specific force z (less 1 g) = a_z
YAW = ((5, None, 5, None),)                      # angular rate z = yaw'
SUBPROBLEMS = (SURGE, SWAY, HEAVE, YAW)
TILTS = (3, 4)  # roll and pitch: their rate within the tilt rate limit beyond the vehicle's (angular rate x, y)
# the workspace's extremes as the local search finds them, widened by a percent: searched from four
# times as many starts, none lies further than 0.3 % beyond them (tests/platform/test_cueing_bound.py)
WIDEN = 1.01


@dataclass(frozen=True)
class CueingBound:
    """The floor under every cueing's perceived error on a drive, and the platform motion that
    reaches it (in the relaxed model): per channel that motion's felt error (rms past the threshold,
    in thresholds), the excursions it was allowed, the tilt rate limit, the samples' step."""
    perceived_error: float    # the floor: the program's dual bound, under its every feasible point
    reached: float            # the motion found, by the measure: above the floor by the solver's tolerance
    channels: dict[str, float]
    times: np.ndarray
    platform: np.ndarray      # n x 6: the best motion, in the six channels
    excursions: np.ndarray    # n x 6: its DOFs from neutral (x, y, z [m], roll, pitch, yaw [rad])
    ranges: np.ndarray        # 6 x 2: each DOF's excursion allowed, least and largest
    tilt_rate_limit: float    # [rad/s] roll's (and pitch's, unless pitch_rate_limit)
    step: float               # [s]
    pitch_rate_limit: float | None = None  # [rad/s] pitch's own (tilt.pitch_rate_limit), None: tilt_rate_limit


def excursion_ranges(core: Core, leg_length: tuple[float, float], joint_angle: float, starts: int = 3,
                     seed: int = 0) -> np.ndarray:
    """Each DOF's least and largest excursion from the neutral pose (6 x 2) over every pose whose
    legs are within `leg_length` [m] and whose joints tilt no more than `joint_angle` [rad] from
    their neutral direction, the other five DOFs free: scipy's SLSQP each way from several starts
    (neutral, neutral nudged that way, and the `starts` poses furthest that way of 20000 drawn
    within +-1 m and +-60 deg that keep the limits), the furthest it reaches."""
    from scipy.optimize import minimize
    neutral = core.neutral_pose

    def margins(pose: np.ndarray) -> np.ndarray:
        k = core.pose_kinematics(pose)
        length, lower, upper = (k[name].reshape(-1, 6) for name in ("length", "lower_angle", "upper_angle"))
        return np.concatenate([length - leg_length[0], leg_length[1] - length, joint_angle - lower,
                               joint_angle - upper], axis=1).squeeze()

    wide = np.array([1.0, 1.0, 1.0, np.pi / 3, np.pi / 3, np.pi / 3])
    drawn = neutral + np.random.default_rng(seed).uniform(-wide, wide, size=(20_000, 6))
    drawn = drawn[(margins(drawn) >= 0.0).all(axis=1)]
    out = np.zeros((6, 2))
    for dof in range(6):
        for side, sign in enumerate((-1.0, 1.0)):
            furthest = drawn[np.argsort(-sign * drawn[:, dof])[:starts]]
            best = 0.0
            for start in [neutral, neutral + sign * 1e-3 * np.eye(6)[dof], *furthest]:
                found = minimize(lambda pose: -sign * (pose[dof] - neutral[dof]), start, method="SLSQP",
                                 constraints=[{"type": "ineq", "fun": margins}], options={"maxiter": 500, "ftol": 1e-12})
                if np.all(margins(found.x) > -1e-9):
                    best = max(best, sign * (found.x[dof] - neutral[dof]))
            out[dof, side] = sign * best
    return out


class _Program:
    """A conic program's rows built block by block: variables by name (each n long), equality and
    inequality rows, second-order cones; Clarabel's A x + s = b, s in the cones."""

    def __init__(self, n: int, step: float):
        self.n, self.step, self.size, self.blocks = n, step, 0, {}
        self.equal: list[tuple[sp.spmatrix, np.ndarray]] = []
        self.less: list[tuple[sp.spmatrix, np.ndarray]] = []
        self.cones: list[tuple[sp.spmatrix, np.ndarray]] = []
        self.cost: dict[int, float] = {}

    def variable(self, name: str, length: int | None = None) -> slice:
        length = self.n if length is None else length
        self.blocks[name] = slice(self.size, self.size + length)
        self.size += length
        return self.blocks[name]

    def rows(self, terms: list[tuple[str, sp.spmatrix]]) -> sp.spmatrix:
        """A block of rows: the sum of (variable, its coefficients) over the variables so far."""
        given = dict(terms)
        height = terms[0][1].shape[0]
        return sp.hstack([sp.csr_matrix(given[name]) if name in given else sp.csr_matrix((height, b.stop - b.start))
                          for name, b in self.blocks.items()], format="csr")

    def solve(self) -> tuple[np.ndarray, float]:
        """Its solution and a bound under its optimum (Clarabel's dual objective: the two meet to the
        solver's tolerance, about 1e-8 relative)."""
        import clarabel
        q = np.zeros(self.size)
        for k, v in self.cost.items():
            q[k] = v
        widen = [sp.hstack([m, sp.csr_matrix((m.shape[0], self.size - m.shape[1]))], format="csr")
                 for m, _ in self.equal + self.less + self.cones]
        A = sp.vstack(widen, format="csc")
        b = np.concatenate([v for _, v in self.equal + self.less + self.cones])
        cones = [clarabel.ZeroConeT(sum(m.shape[0] for m, _ in self.equal)),
                 clarabel.NonnegativeConeT(sum(m.shape[0] for m, _ in self.less))]
        cones += [clarabel.SecondOrderConeT(m.shape[0]) for m, _ in self.cones]
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        settings.equilibrate_max_iter = 100  # its rows' scales span the integrators' h^2 to the cones' 1/sqrt(n)
        settings.max_iter = 400
        solver = clarabel.DefaultSolver(sp.csc_matrix((self.size, self.size)), q, A, b, cones, settings)
        solution = solver.solve()
        if str(solution.status) not in ("Solved", "AlmostSolved"):
            raise RuntimeError(f"the bound's conic program was not solved: {solution.status}")
        # the dual objective: no point of the program, feasible to the solver's tolerance, lies below it
        # (weak duality); nor below 0 (a sum of norms)
        return np.array(solution.x), max(0.0, float(solution.obj_val_dual))


def _motion_rows(prog: _Program, problem: tuple, h: float, ranges: np.ndarray, rate_bound: dict[int, np.ndarray]) -> None:
    """A sub-problem's DOFs: each within its range; a translation's acceleration, constant between
    samples, into its rate and position (p+ = p + h v + h^2/2 a, v+ = v + h a); a rotation's rate,
    constant between samples, into its angle, a tilt's within `rate_bound`; all from rest at neutral."""
    n = prog.n
    eye, shift = sp.identity(n, format="csr"), sp.eye(n, k=-1, format="csr")  # x_k, x_{k-1}
    first = sp.csr_matrix(([1.0], ([0], [0])), shape=(1, n))
    dofs = sorted({d for _, t, r, _ in problem for d in (t, r) if d is not None})
    translations = {t for _, t, _, _ in problem if t is not None}
    for dof in dofs:
        prog.variable(f"pos{dof}"), prog.variable(f"rate{dof}")
        if dof in translations:
            prog.variable(f"acc{dof}")
        lo, hi = ranges[dof]
        prog.less.append((prog.rows([(f"pos{dof}", eye)]), np.full(n, hi)))
        prog.less.append((prog.rows([(f"pos{dof}", -eye)]), np.full(n, -lo)))
        integrate = sp.csr_matrix(eye - shift)
        if dof in translations:
            prog.equal.append((prog.rows([(f"rate{dof}", integrate), (f"acc{dof}", -h * shift)]), np.zeros(n)))
            prog.equal.append((prog.rows([(f"pos{dof}", integrate), (f"rate{dof}", -h * shift),
                                          (f"acc{dof}", -0.5 * h * h * shift)]), np.zeros(n)))
            prog.equal.append((prog.rows([(f"acc{dof}", first)]), np.zeros(1)))
        else:
            prog.equal.append((prog.rows([(f"pos{dof}", integrate), (f"rate{dof}", -h * shift)]), np.zeros(n)))
            prog.equal.append((prog.rows([(f"rate{dof}", first)]), np.zeros(1)))
            if dof in rate_bound:
                prog.less.append((prog.rows([(f"rate{dof}", eye)]), rate_bound[dof]))
                prog.less.append((prog.rows([(f"rate{dof}", -eye)]), rate_bound[dof]))


def _channel_terms(translation: int | None, tilt: int | None, weight: float | None, gravity: float,
                   eye: sp.spmatrix) -> list[tuple[str, sp.spmatrix]]:
    """A channel's motion u as the sub-problem's variables: a translation's acceleration plus its
    tilt's share of gravity, or a rotation's rate."""
    if translation is None:
        return [(f"rate{tilt}", eye)]
    return [(f"acc{translation}", eye)] + ([(f"pos{tilt}", weight * gravity * eye)] if tilt is not None else [])


def _felt_rows(prog: _Program, channel: int, terms: list, organ: Vestibular, felt_vehicle: np.ndarray,
               dead_zone: bool = True) -> None:
    """A channel's perception (the organ's modes, x_k = e x_{k-1} + (i0 - i1) u_{k-1} + i1 u_k from 0),
    its felt error w = perceived platform - perceived vehicle - d with the dead zone |d| <= threshold
    (without it d = 0: every error counts, as in the MPC's quadratic cost), and its rms in thresholds
    as a cone t >= |w| / (threshold sqrt(n)), t in the cost."""
    n = prog.n
    eye, shift = sp.identity(n, format="csr"), sp.eye(n, k=-1, format="csr")
    modes, direct = organ.recursions(prog.step)  # the measure's own discretisation
    for m, (decay, previous, now, _) in enumerate(modes):
        prog.variable(f"mode{channel}.{m}")
        prog.equal.append((prog.rows([(f"mode{channel}.{m}", eye - decay * shift)]
                                     + [(name, -(previous * shift + now * eye) @ c) for name, c in terms]), np.zeros(n)))
    prog.variable(f"dead{channel}"), prog.variable(f"felt{channel}")
    perceived = [(f"mode{channel}.{m}", r * eye) for m, (_, _, _, r) in enumerate(modes)]
    perceived += [(name, direct * c) for name, c in terms] if direct else []
    prog.equal.append((prog.rows([(f"felt{channel}", eye), (f"dead{channel}", eye)] + [(name, -c) for name, c in perceived]),
                       -felt_vehicle))
    threshold = float(THRESHOLDS[channel])
    zone = threshold if dead_zone else 0.0
    prog.less.append((prog.rows([(f"dead{channel}", eye)]), np.full(n, zone)))
    prog.less.append((prog.rows([(f"dead{channel}", -eye)]), np.full(n, zone)))
    cone = prog.variable(f"norm{channel}", 1)
    prog.cost[cone.start] = 1.0
    scale = 1.0 / (threshold * np.sqrt(n))
    prog.cones.append((sp.vstack([prog.rows([(f"norm{channel}", -sp.identity(1))]),
                                  prog.rows([(f"felt{channel}", -scale * eye)])]), np.zeros(n + 1)))


def least_perceived_error(times: np.ndarray, vehicle: np.ndarray, ranges: np.ndarray, tilt_rate_limit: float,
                          gravity: float = 9.81, step: float = 0.01,
                          organs: tuple[Vestibular, ...] = ORGANS, dead_zone: bool = True,
                          pitch_rate_limit: float | None = None) -> CueingBound:
    """The least perceived error (cosim.platform.perception's measure, by `organs`) of any platform
    motion for the vehicle's motion (n x 6 at `times`, the six channels as vehicle_motion gives
    them), knowing all of it, in the relaxed model above: each DOF within its `ranges` (6 x 2, from
    neutral), roll and pitch each turning no faster than `tilt_rate_limit` [rad/s] (pitch than
    `pitch_rate_limit` where given) beyond the vehicle's own rate about that axis, from rest at neutral, accelerations and rates constant
    between samples `step` apart. The floor is the program's dual bound; the motion found is
    measured by the project's measure (`reached`: the same number to the solver's tolerance).
    dead_zone False: the program counts every error, below the thresholds too (as the MPC's quadratic
    cost does); its optimum is then no floor (`perceived_error`: that objective), but `reached`, its
    motion by the measure, shows what ignoring the dead zone costs."""
    grid = np.arange(times[0], times[-1] + 0.5 * step, step)
    grid = grid[grid <= times[-1] + 1e-12]
    n = len(grid)
    at = np.column_stack([np.interp(grid, times, vehicle[:, c]) for c in range(6)])
    felt_vehicle = np.column_stack([organs[c].perceive(grid, at[:, c]) for c in range(6)])
    limits = dict(zip(TILTS, (tilt_rate_limit, pitch_rate_limit or tilt_rate_limit)))  # roll about x, pitch about y
    rate_bound = {dof: limits[dof] + np.abs(at[:, dof]) for dof in TILTS}
    platform, excursions, floor = np.zeros((n, 6)), np.zeros((n, 6)), 0.0
    eye = sp.identity(n, format="csr")
    for problem in SUBPROBLEMS:
        prog = _Program(n, step)
        _motion_rows(prog, problem, step, ranges, rate_bound)
        for channel, translation, tilt, weight in problem:
            _felt_rows(prog, channel, _channel_terms(translation, tilt, weight, gravity, eye), organs[channel],
                       felt_vehicle[:, channel], dead_zone)
        x, least = prog.solve()
        floor += least
        for channel, translation, tilt, weight in problem:
            platform[:, channel] = sum(c @ x[prog.blocks[name]]
                                       for name, c in _channel_terms(translation, tilt, weight, gravity, eye))
        for name, block in prog.blocks.items():
            if name.startswith("pos"):
                excursions[:, int(name[3:])] = x[block]
    channels = quality(perceive(grid, at, platform, step=step, organs=organs))
    return CueingBound(floor, perceived_error(channels), {c: q.rms_felt_error / q.threshold for c, q in zip(CHANNELS, channels)},
                       grid, platform, excursions, np.asarray(ranges, float), float(tilt_rate_limit), step,
                       float(pitch_rate_limit) if pitch_rate_limit else None)


def scene_bound(scene, tilt_rate_limit: float | None = None, step: float = 0.01,
                organs: tuple[Vestibular, ...] = ORGANS, dead_zone: bool = True,
                pitch_rate_limit: float | None = None) -> CueingBound:
    """The floor under every cueing of a scene's vehicle motion (least_perceived_error): its
    platform's excursions within its mechanics' stroke and joint angle (the margins not taken off;
    widened by WIDEN),
    its tilt rate limits (the scene's `tilt.rate_limit` and `tilt.pitch_rate_limit`, or the cueing
    FMU's defaults; or as given),
    the vehicle's motion as the cueing FMU reads it from the scene's file (dead_zone: as
    least_perceived_error's)."""
    from ..core import gravity_of
    from ..run.alone import play_cueing
    from ..run.compile import CUEING_ALGORITHMS, scene_cueing, scene_values
    from .cueing import _core, scene_limits
    mechanics, _ = scene_values(scene)
    values = {**scene_cueing(scene, mechanics), "algorithm": CUEING_ALGORITHMS["classical"]}  # the motion it reads, cheaply
    from ...engine.artifacts import fmu_path
    from ...engine.checks import variables
    defaults = variables(fmu_path("cueing"))
    if tilt_rate_limit is None:
        tilt_rate_limit = float(values.get("tilt.rate_limit", defaults["tilt.rate_limit"].start))
    if pitch_rate_limit is None:
        pitch_rate_limit = float(values.get("tilt.pitch_rate_limit", defaults["tilt.pitch_rate_limit"].start))
    times, _, _, taken = play_cueing(values, scene.duration, step)
    gravity = float(np.linalg.norm(gravity_of(mechanics)))
    limits = scene_limits(scene)
    ranges = WIDEN * excursion_ranges(_core(scene), limits.leg_length, limits.joint_angle)
    return least_perceived_error(times, vehicle_motion(taken[:, :3], taken[:, 3:], gravity), ranges,
                                 float(tilt_rate_limit), gravity, step, organs, dead_zone, pitch_rate_limit or None)
