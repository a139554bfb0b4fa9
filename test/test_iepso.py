# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""IEPSO (eq. 3-5) with polish: exact answers against the reference, determinism, any arm."""
import itertools

import numpy as np
import pytest

from trajplan_ros.kinematics import ArmModel, paper_arm
from trajplan_ros.search.goal import Goal
from trajplan_ros.search.iepso import iepso
from trajplan_ros.search.objective import Objective
from trajplan_ros.tools.bench.reference import exact_minimum

ARM = paper_arm()
TARGET = np.array([0.151171, 0.19162, 0.172124])


@pytest.mark.parametrize('mode', ['free', 'radial'])
def test_paper_target_exact_optimum(mode):
    obj = Objective(ARM, Goal(TARGET, mode=mode), np.zeros(5))
    ref = exact_minimum(ARM, TARGET, np.zeros(5), mode=mode)
    res = iepso(obj, seed=0)
    assert res.error <= 1e-9
    assert res.motion_time <= ref.motion_time_s * 1.001
    assert res.converged


def test_random_goals_and_starts_reach_the_exact_optimum():
    rng = np.random.default_rng(2024)
    for i in range(12):
        goal = ARM.tool(rng.uniform(ARM.lower, ARM.upper, (1, 5)))[0][0]
        start = rng.uniform(ARM.lower, ARM.upper)
        res = iepso(Objective(ARM, Goal(goal), start), seed=i)
        ref = exact_minimum(ARM, goal, start)
        assert res.error <= 1e-6, i
        assert res.motion_time <= ref.motion_time_s * 1.001, i


#: Goals, starts and seeds from ``trajplan bench --mode free --random-starts --seed 1`` on which
#: the run once stopped on candidates that had reached eps (5e-6 m) but not settled: eq. (17)'s
#: reward then made the final choice (least F) a slower, exact candidate, 9 % to 124 % slower.
SETTLING_CASES = [
    ([0.15036416089968185, -0.044100728553377204, 0.19194128270115351],
     [1.9794648820220377, -1.0547589972062985, -2.0816170580672675, 0.8515288785937485,
      0.42139317733827175], 850240737),
    ([0.037012240911437434, 0.07800017788119008, 0.29652812184469896],
     [1.2404971382828909, 1.3520022491493386, -0.009388970947007191, -0.32200782139204476,
      1.4993844149557196], 434641378),
    ([-0.17762650954735532, -0.055488231657812574, 0.1248438306288801],
     [-1.9871957837668925, -0.5097288981216355, 1.6542571824097214, -1.67478643867628,
      1.4647038157335768], 1951443985),
    ([-0.04960909935285084, 0.07168191538497189, 0.10263713907518074],
     [0.9884030348676291, -1.43489204438269, -1.1052524584438703, 0.5866752730552034,
      -1.7669233922189753], 1210666150),
    ([0.028128742846227323, -0.13088536041340404, 0.1428784825965398],
     [-1.8486782481170194, 0.05824931233695496, 0.38420078527362955, 0.80599713655789,
      1.9240306592508398], 206502220),
]


@pytest.mark.parametrize('goal, start, seed', SETTLING_CASES)
def test_agreement_waits_for_settled_candidates(goal, start, seed):
    res = iepso(Objective(ARM, Goal(np.array(goal)), np.array(start)), seed=seed)
    ref = exact_minimum(ARM, np.array(goal), np.array(start))
    assert res.error <= 1e-9
    assert res.motion_time <= ref.motion_time_s * 1.001


#: Goals (bench --mode free --random-starts, seeds 3, 6 and 9) whose fastest solution lies on
#: the same curve of solutions as the swarms' answer but beyond a joint-limit gap or a bump in
#: the motion time, where the local polish cannot see it.
CURVE_CASES = [
    ([-0.20409769935647995, -0.10456289784470171, 0.04748181220501197],
     [1.8724742996841428, -0.31727661434101706, 1.1238982511057185, -1.2932052740329412,
      2.6120178318873677], 889701985),
    ([-0.14682996654309383, 0.12331634061488152, 0.04185274036427678],
     [0.48094187837659463, 0.48890919566823055, 2.1305881636552755, -2.300091789244345,
      1.9564444529993166], 1358944411),
    ([-0.14732031347343708, 0.09145416470637528, -0.10225488643503208],
     [-0.30899230476008954, -0.41172085964899474, -2.162433944358706, -2.0079611188310844,
      1.2132179509099315], 1887933805),
]


#: Radial goals (bench --mode radial --random-starts, seeds 5 and 7) whose fastest solution lies
#: on the position-only curve through the swarms' answer.
RADIAL_CURVE_CASES = [
    ([0.04304774236358056, 0.2654821487746038, 0.1676819984043166],
     [-0.9933372358905286, -0.8106853184496781, 1.0827542003880914, -1.2842389309609377,
      1.9539684046866395], 1107168228),
    ([-0.23800352631325447, 0.1666255355621998, 0.14167257538029973],
     [0.14119010062413162, -1.1953064888478515, 1.3024334124714847, -0.16295662014572398,
      -2.727379586408286], 836908462),
]


@pytest.mark.parametrize('goal, start, seed, mode',
                         [(*case, 'free') for case in CURVE_CASES]
                         + [(*case, 'radial') for case in RADIAL_CURVE_CASES])
def test_optima_beyond_a_gap_in_the_curve_are_found(goal, start, seed, mode):
    # with earlier settings the swarms settled elsewhere on these (test_solution_curve has
    # goals on which today's swarms do, and the curve search is what finds the optimum)
    obj = Objective(ARM, Goal(np.array(goal), mode=mode), np.array(start))
    ref = exact_minimum(ARM, np.array(goal), np.array(start), mode=mode)
    res = iepso(obj, seed=seed)
    assert res.error <= 1e-9
    assert res.motion_time <= ref.motion_time_s * 1.001


def test_same_seed_same_answer_bit_for_bit():
    obj = Objective(ARM, Goal(TARGET), np.array([0.3, -0.2, 0.1, 0.4, 0.0]))
    a, b = iepso(obj, seed=42), iepso(obj, seed=42)
    assert a.x.tobytes() == b.x.tobytes()
    np.testing.assert_array_equal(a.history_fun, b.history_fun)


#: Goals, starts, seeds and results (x and F as float.hex, nit, nfev), first recorded from the
#: pre-rewrite implementation of ``iepso`` (commit b21c64f) and reproduced bit for bit by its
#: rewrite into the steps of section III; re-recorded when issue 13 changed the search on
#: purpose (radial = goal ray, the curve search, fewer swarms and polish candidates, the answer
#: chosen by time then travel). Goals and starts drawn with default_rng(11), default options; a
#: change to any of these values is a change of behaviour, not a refactoring. The radial cases
#: include swarm restarts (10 iterations) and a goal that is never reached (145 iterations,
#: F > 0). Changed by the polish's converged test (trust radius 1e-9 rad), the curve search's
#: early stop and its longer seed polish: the third free case lies on a tie (a stretch of
#: equally fast goals of equal travel to 1e-15 rad) and moved 1e-8 rad along it; the second
#: radial case (seed 17 before) now settles in 5 iterations, so seed 9 keeps a restart; the
#: unreachable goal stops after fewer iterations at an F 0.14 % higher (7296 against 7285).
#: Re-recorded for the compiled forward kinematics (its own rounding): the third free case, on
#: that tie, moved 1.8e-11 rad along it; the others hold to 1e-12.
PINNED_CASES = [
    ('free', [-0.015221095704841387, -0.08387239290283476, 0.05328739294780818],
     [2.0178969058777003, -1.3495635620873112, -1.7446491611020927, 1.36788263737217,
      0.7658171994444922], 0,
     ['0x1.642a55949843bp+0', '0x1.064e224a02d57p+0', '-0x1.c29d04c6db53cp+0',
      '0x1.921fb54442d18p+0'],
     '-0x1.84210ab0c9f80p+3', 5, 1920),
    ('free', [0.15445187745280403, -0.10964909434840381, 0.08042901569238504],
     [1.3573546110550856, 0.5352035594776292, 0.058350277609713785, 0.8511219937593903,
      0.3083490083100373], 1,
     ['-0x1.3c160073325dcp-1', '-0x1.20aaeee7ce5cfp-4', '0x1.ed851b9193969p-1',
      '-0x1.1fa376310d472p+0'],
     '-0x1.c40be02f65adcp+3', 5, 1920),
    ('free', [0.08748986337716974, -0.10483479260629924, 0.27685319290871546],
     [0.4316327009844585, -0.8315757060073955, 1.4240965968804047, 1.0498164031577453,
      -2.3325717791736853], 2,
     ['-0x1.c02ca1ee125b1p-1', '-0x1.5f487590ab85fp-5', '0x1.2de74a7ae45d2p+0',
      '0x1.02d49b32457acp+0'],
     '-0x1.1771303e3c23ep+4', 5, 1920),
    ('radial', [-0.1707871609068368, -0.1725230119188646, 0.02857422422714151],
     [1.396784460314116, -1.238408695988162, -1.4027333547080008, 0.37282464438265306,
      2.941761814355817], 0,
     ['0x1.94b66e5675e11p-1', '-0x1.a2e1ada4c7a8bp-1', '-0x1.d91280b5932bbp+0',
      '-0x1.3662422537614p+0'],
     '-0x1.012dd37d74d26p+4', 5, 2880),
    ('radial', [-0.15843545623775315, -0.1139806517509398, -0.11977649013223965],
     [-1.3119271550540221, -0.568598265143258, 1.5226707374615125, -1.8498789144108139,
      -1.3833524008713862], 9,
     ['0x1.3f4d551127a18p-1', '-0x1.5e8b0f015aadap+0', '-0x1.0830f011ccb5cp+1',
      '-0x1.4fe4babad23cap+0'],
     '-0x1.8444730577238p+2', 10, 5720),
    ('radial', [0.1114909755743878, 0.12257008152023864, -0.0723362566562846],
     [1.0134618115124985, 0.834946683548992, 2.3085378881739445, -0.10513934045112361,
      1.772140595738609], 63,
     ['0x1.b0721679bbe00p-1', '0x1.23b83b9244ce3p-2', '0x1.2d97c7f3321d2p+1',
      '0x1.4651e71525d9ep-1'],
     '0x1.c7fa45390a36ep+12', 145, 82400),
]


@pytest.mark.parametrize('mode, goal, start, seed, x_hex, fun_hex, nit, nfev', PINNED_CASES)
def test_results_are_pinned(mode, goal, start, seed, x_hex, fun_hex, nit, nfev):
    # to 1e-12, not bit for bit: numpy's sin and cos take other SIMD paths on other CPUs, which
    # moves the last bits of a pose (seen: 2 ulp of one radial answer on another machine); F
    # holds the reward of an error of ~1e-17 m, which those bits move by a few parts in 1e7
    res = iepso(Objective(ARM, Goal(np.array(goal), mode=mode), np.array(start)), seed=seed)
    np.testing.assert_allclose(res.x, [float.fromhex(v) for v in x_hex], rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.fun, float.fromhex(fun_hex), rtol=1e-5)
    assert (res.nit, res.nfev) == (nit, nfev)


def test_papers_iepso_alone_is_pinned_bit_for_bit():
    # recorded from the pre-rewrite implementation too (see PINNED_CASES); without the polish,
    # which settles slightly different swarms on the same exact answer, these values change
    # with any change in the swarm arithmetic, down to the association of eq. (4)'s sum
    res = iepso(Objective(ARM, Goal(TARGET), np.zeros(5)), seed=3, polish=False, swarms=2,
                max_iter=60)
    assert [v.hex() for v in res.x] == ['0x1.ce0f32e3f43b7p-1', '0x1.d4eb9ede121ffp-1',
                                        '0x1.b1f70255d21d9p-1', '0x1.88cea0dad5ef4p+0']
    # F re-recorded for the compiled rule base (single precision, summed in another order):
    # 1703.94406 against 1703.94377 (2e-7 relative); the swarm's x is the same bit for bit
    assert res.fun.hex() == '0x1.a9fc6b7eb9e44p+10'
    assert (res.nit, res.nfev, res.converged) == (60, 4880, False)


def test_history_is_a_monotone_record_of_the_best():
    res = iepso(Objective(ARM, Goal(TARGET), np.zeros(5)), seed=3, polish=False, max_iter=150)
    assert res.nit == res.history_fun.size == res.history_error.size
    assert np.all(np.diff(res.history_fun) <= 0)
    assert res.nfev >= res.nit * 40


def test_papers_iepso_alone_gets_close_but_not_exact():
    res = iepso(Objective(ARM, Goal(TARGET), np.zeros(5)), seed=1, polish=False, swarms=1)
    assert res.error < 5e-6            # within the reward threshold eps
    assert res.fun < 0


@pytest.mark.parametrize('n', [2, 3, 6, 7])
def test_other_chains_reach_goals_from_their_own_configurations(n):
    rng = np.random.default_rng(100 + n)
    arm = ArmModel.from_dh(
        a=rng.uniform(0.05, 0.15, n), alpha=rng.choice([0.0, np.pi / 2, -np.pi / 2], n),
        d=rng.uniform(0.0, 0.1, n), lower=-np.full(n, 2.6), upper=np.full(n, 2.6))
    for k in range(3):
        goal = arm.tool(rng.uniform(arm.lower, arm.upper, (1, n)))[0][0]
        res = iepso(Objective(arm, Goal(goal), np.zeros(n)), seed=k)
        assert res.error <= 1e-6, (n, k)


def interrupt_after(k: int, reason: str = 'enough'):
    """Return an interrupt that carries on for its first k asks, then gives ``reason``."""
    asks = itertools.count()
    return lambda: reason if next(asks) >= k else None


#: Out of reach: IEPSO searches it for dozens of iterations, then stops unconverged.
FAR = np.array([0.36, 0.0, 0.05])


@pytest.mark.parametrize('goal, polish, max_iter', [(TARGET, True, 1000), (FAR, True, 1000),
                                                    (TARGET, False, 400), (FAR, False, 120)])
def test_an_interrupt_that_never_fires_changes_nothing(goal, polish, max_iter):
    obj = Objective(ARM, Goal(goal), np.zeros(5))
    asked = []
    plain = iepso(obj, seed=2, polish=polish, max_iter=max_iter)
    watched = iepso(obj, seed=2, polish=polish, max_iter=max_iter,
                    interrupt=lambda: asked.append(1))                  # None, and counts asks
    assert watched.x.tobytes() == plain.x.tobytes() and watched.fun == plain.fun
    assert (watched.nit, watched.nfev, watched.converged) == (plain.nit, plain.nfev,
                                                              plain.converged)
    assert watched.history_fun.tobytes() == plain.history_fun.tobytes()
    assert watched.interrupted is plain.interrupted is None
    # asked after every iteration but the one that the stopping rule ends, and after every
    # polish step besides
    stopped_by_rule = plain.nit < max_iter
    assert len(asked) >= plain.nit - stopped_by_rule


@pytest.mark.parametrize('polish', [True, False])
def test_an_interrupt_ends_the_run_with_the_best_so_far(polish):
    obj = Objective(ARM, Goal(FAR), np.zeros(5))
    res = iepso(obj, seed=2, polish=polish, max_iter=120, interrupt=interrupt_after(7, 'late'))
    assert res.interrupted == 'late' and not res.converged
    # asked after every iteration (eight) and, with the polish, after its steps too
    assert res.nit == res.history_fun.size == 8 if not polish else res.nit < 8
    assert res.fun == pytest.approx(res.history_fun.min(), rel=1e-6)


def test_bad_settings_raise():
    with pytest.raises(ValueError):
        iepso(Objective(ARM, Goal(TARGET), np.zeros(5)), population=1)
