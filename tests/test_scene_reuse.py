"""Compile once, set in place (simgrip.sim.reuse): a reused scene is bit-identical to a fresh build.

Over seeded random parameter sequences, for every planar grip (free, I, II, III; one and two fingers) and
K-finger grippers (K = 2, 3, 4; box, cylinder, sphere; the K = 4 cradle), the scene the cache hands out is
compared with a fresh :func:`build_scene` / :func:`build_gripper` of the same arguments: every field of the
compiled model (each array byte for byte, each scalar, the option and statistics structs) and the state
after the settle (every array and number of the settled state but the timings).  Exact equality: nothing
here is a tolerance, the two must be the same bits.  Each cached scene is settled before it is reused, so
whatever a settle writes into the model (time step, damping, contact softness) must not leak either.
"""

from __future__ import annotations

import dataclasses
import math
import threading

import mujoco
import numpy as np
import pytest

from simgrip.params import DimensionlessParams, PhysicalParams
from simgrip.profiles import Concentrated, Uniform
from simgrip.scenes import build_scene
from simgrip.settle import settle
from simgrip.gripper.settle import settle_gripper
from simgrip.gripper import reuse as gripper_reuse
from simgrip.sim import reuse
from simgrip.gripper.scene import build_gripper

_SKIP_STATE = {"wall_time_s", "build_time_s"}


def model_fields(m: mujoco.MjModel) -> dict:
    """Every field of a compiled model as bytes (arrays: dtype, shape and bytes; scalars; opt/stat/vis)."""
    out = {}
    for name in dir(m):
        if name.startswith("_"):
            continue
        try:
            v = getattr(m, name)
        except Exception:  # pragma: no cover - a field MuJoCo refuses to read
            continue
        if isinstance(v, np.ndarray):
            out[name] = (v.dtype.str, v.shape, v.tobytes())
        elif isinstance(v, (int, float, bool, bytes, str)) and not callable(v):
            out[name] = repr(v) if not isinstance(v, float) else v.hex()
    for sub in ("opt", "stat", "vis"):
        out.update(_struct_fields(getattr(m, sub), sub))
    return out


def _struct_fields(obj, prefix: str) -> dict:
    out = {}
    for name in dir(obj):
        if name.startswith("_"):
            continue
        v = getattr(obj, name)
        key = f"{prefix}.{name}"
        if isinstance(v, np.ndarray):
            out[key] = (v.dtype.str, v.shape, v.tobytes())
        elif isinstance(v, float):
            out[key] = v.hex()
        elif isinstance(v, (int, bool, str)):
            out[key] = repr(v)
        elif not callable(v) and hasattr(v, "__class__") and type(v).__module__.startswith("mujoco"):
            out.update(_struct_fields(v, key))
    return out


def assert_same_model(a: mujoco.MjModel, b: mujoco.MjModel) -> None:
    fa, fb = model_fields(a), model_fields(b)
    assert fa.keys() == fb.keys()
    differ = sorted(k for k in fa if fa[k] != fb[k])
    assert not differ, f"model fields differ from a fresh build: {differ}"
    assert len(fa) > 300  # the comparison did see the model (every array, option and statistic)


#: The sparse constraint Jacobian's index arrays: with a dense Jacobian (``mj_isSparse`` false) MuJoCo never
#: writes them, they show whatever the arena held (zeros in a new MjData, a settle's leftovers in a reused one),
#: and nothing reads them.  With a sparse Jacobian they are written and compared like every other array.
_SPARSE_ONLY = {"efc_J_rownnz", "efc_J_rowadr", "efc_J_rowsuper", "efc_J_colind"}


def assert_same_data(a: mujoco.MjData, b: mujoco.MjData, model: mujoco.MjModel) -> None:
    """Every array of two MjData (the start a scene is handed out at) byte for byte."""
    differ = []
    unwritten = set() if mujoco.mj_isSparse(model) else _SPARSE_ONLY
    for name in dir(a):
        if name.startswith("_") or name in unwritten:
            continue
        try:
            va, vb = getattr(a, name), getattr(b, name)
        except Exception:  # pragma: no cover - a field MuJoCo refuses to read
            continue
        if isinstance(va, np.ndarray) and (va.shape != vb.shape or va.tobytes() != vb.tobytes()):
            differ.append(name)
    assert not differ, f"data fields differ from a fresh build's: {differ}"


def _plain(v):
    """A settled state's value as something == compares bit-exactly (arrays as bytes, floats as hex)."""
    if isinstance(v, np.ndarray):
        return ("a", v.dtype.str, v.shape, v.tobytes())
    if isinstance(v, float):
        return ("f", v.hex())
    if isinstance(v, (list, tuple)):
        return tuple(_plain(x) for x in v)
    if isinstance(v, dict):
        return tuple(sorted((k, _plain(x)) for k, x in v.items()))
    if dataclasses.is_dataclass(v):
        return tuple((f.name, _plain(getattr(v, f.name))) for f in dataclasses.fields(v) if f.name not in _SKIP_STATE)
    return v


def assert_same_state(a, b) -> None:
    pa, pb = _plain(a), _plain(b)
    differ = [x[0] for x, y in zip(pa, pb) if x != y]
    assert not differ, f"settled state differs from a fresh build's: {differ}"


def scribble(scene) -> None:
    """Write into the handed-out scene what a caller may (the dynamic settles set these): the next reuse
    must undo it all."""
    m, d = scene.model, scene.data
    m.opt.timestep, m.opt.integrator, m.opt.impratio = 0.123, int(mujoco.mjtIntegrator.mjINT_EULER), 7.0
    m.opt.gravity[:] = [1.0, 2.0, 3.0]
    m.dof_damping[:] = 5.0
    m.jnt_stiffness[:] *= 2.0
    m.body_mass[1:] += 1.0
    if m.npair:
        m.pair_solref[:] = [0.5, 0.5]
        m.pair_friction[:] = 9.0
    d.qfrc_applied[:] = 1.0
    d.qpos[:] += 0.1
    d.qacc_warmstart[:] = 3.0


def _params(rng, grip: str) -> DimensionlessParams:
    M = 0.0 if rng.random() < 0.25 else float(rng.uniform(0.2, 6.0))  # M = 0: the inertia floor, gravcomp
    b = float(rng.uniform(0.45, 0.75))
    return DimensionlessParams(D=float(rng.uniform(0.5, 3.0)), M=M, b=b, mu_s=float(rng.uniform(0.3, 3.0)),
                               gamma=float(rng.uniform(0.75, 0.9)))


def _profile(rng):
    if rng.random() < 0.3:
        return Concentrated(float(rng.uniform(2.0, 6.0)), float(rng.uniform(0.5, 3.0)), p=-1)
    return Uniform(float(rng.uniform(-4.0, -1.0)))


PLANAR = [("free", 1, 10), ("I", 1, 10), ("II", 1, 10), ("III", 1, 10), ("I", 2, 10), ("III", 2, 10),
          ("I", 1, 64), ("III", 1, 64)]  # n = 64: MuJoCo's sparse Jacobian (auto above 60 dofs)


@pytest.mark.parametrize("grip,fingers,n", PLANAR)
def test_planar_reuse_is_bit_identical(grip, fingers, n):
    rng = np.random.default_rng(1900 + PLANAR.index((grip, fingers, n)))
    reuse.clear()
    for _ in range(4 if n < 60 else 3):
        params, prof = _params(rng, grip), _profile(rng)
        if n >= 60:  # the Grip III links paired with the corner (structure) follow gamma: keep it, and b
            params = dataclasses.replace(params, b=0.6, gamma=0.8)
        kw = {"fingers": fingers} if fingers != 1 else {}
        try:
            fresh = build_scene(grip, params, prof, n, **kw)
        except ValueError:
            with pytest.raises(ValueError):  # the cache refuses what the builder refuses
                reuse.build_scene(grip, params, prof, n, **kw)
            continue
        used = reuse.build_scene(grip, params, prof, n, **kw)
        assert_same_model(used.model, fresh.model)
        assert_same_data(used.data, fresh.data, fresh.model)
        assert used.params == fresh.params and np.array_equal(used.box_half, fresh.box_half)
        assert np.array_equal(used.springs.rest, fresh.springs.rest)
        if fingers == 1:
            method = "dynamics" if grip == "I" and rng.random() < 0.5 else "newton"
            assert_same_state(settle(used, method=method), settle(fresh, method=method))
        scribble(used)
    assert reuse.cache_info()["hits"] >= 1


def test_planar_reuse_physical_params_and_render():
    """SI parameters (rho, g, EI change the links' masses, gravity, stiffness) and the rendering dressing."""
    reuse.clear()
    rng = np.random.default_rng(19)
    for _ in range(3):
        p = PhysicalParams(length=0.1, EI=float(rng.uniform(1e-4, 1e-3)), rho=float(rng.uniform(0.05, 0.2)),
                           g=float(rng.uniform(5.0, 12.0)), m=float(rng.uniform(0.0, 0.05)), b=0.06, mu_s=1.0,
                           gamma=0.08)
        for render in (False, True):
            used = reuse.build_scene("I", p, Uniform(-2.5), 8, render=render)
            assert_same_model(used.model, build_scene("I", p, Uniform(-2.5), 8, render=render).model)
            scribble(used)
    assert reuse.cache_info()["hits"] >= 4


GRIPPERS = [("I", 2, "box"), ("I", 3, "cylinder"), ("II", 3, "sphere"), ("I", 4, "box"), ("II", 4, "cylinder"),
            ("III", 4, "box")]


@pytest.mark.parametrize("grip,K,shape", GRIPPERS)
def test_gripper_reuse_is_bit_identical(grip, K, shape):
    rng = np.random.default_rng(1950 + GRIPPERS.index((grip, K, shape)))
    reuse.clear()
    n = 8
    for i in range(3):
        params = _params(rng, grip)
        if shape == "sphere" or grip == "III":
            prof = Uniform(float(rng.uniform(-3.0, -1.0)))
        else:
            prof = [Uniform(float(rng.uniform(-3.0, -1.0))) for _ in range(K)]  # each finger its own
        kw = dict(fingers=K, workpiece=shape)
        if grip == "III" and i == 2:
            cradle = gripper_reuse.build_gripper(grip, params, prof, n, **kw)
            kw["initial_angles"] = cradle.model.numeric_data[:n].copy()
        elif i == 2:  # a start off the straight fingers: the workpiece (its free joint's qpos0) moves with the tips
            kw["initial_angles"] = rng.uniform(-0.2, 0.0, (K, n))
        try:
            fresh = build_gripper(grip, params, prof, n, **kw)
        except ValueError:
            with pytest.raises(ValueError):
                gripper_reuse.build_gripper(grip, params, prof, n, **kw)
            continue
        used = gripper_reuse.build_gripper(grip, params, prof, n, **kw)
        assert_same_model(used.model, fresh.model)
        assert_same_data(used.data, fresh.data, fresh.model)
        assert np.array_equal(used.size, fresh.size) and np.array_equal(used.reach, fresh.reach)
        if i < 2:
            assert_same_state(settle_gripper(used), settle_gripper(fresh))
        scribble(used)
    assert reuse.cache_info()["hits"] >= 1


def test_structure_is_the_key_and_the_cache_is_bounded():
    reuse.clear()
    p = DimensionlessParams()
    a = reuse.build_scene("I", p, Uniform(-2.0), 6)
    assert reuse.build_scene("I", p, Uniform(-3.0), 6) is a  # same structure: the same scene, set in place
    assert reuse.build_scene("I", p, Uniform(-3.0), 7) is not a  # links
    assert reuse.build_scene("I", p, Uniform(-3.0), 6, fingers=2) is not a  # fingers
    assert reuse.build_scene("I", p, Uniform(-3.0), 6, r_tip=3e-3) is not a  # any other keyword
    assert reuse.build_scene("II", p, Uniform(-3.0), 6) is not a  # grip
    for n in range(8, 8 + reuse.CACHE_SIZE):
        reuse.build_scene("free", p, Uniform(-1.0), n)
    info = reuse.cache_info()
    assert info["size"] == reuse.CACHE_SIZE
    assert reuse.build_scene("I", p, Uniform(-3.0), 6) is not a  # evicted (least recently used)


def test_each_thread_has_its_own_cache():
    reuse.clear()
    p = DimensionlessParams()
    mine = reuse.build_scene("I", p, Uniform(-2.0), 6)
    theirs = []
    t = threading.Thread(target=lambda: theirs.append(reuse.build_scene("I", p, Uniform(-2.0), 6)))
    t.start()
    t.join()
    assert theirs[0] is not mine and theirs[0].model is not mine.model
    assert reuse.build_scene("I", p, Uniform(-2.0), 6) is mine


def test_bad_arguments_are_the_builders_errors():
    reuse.clear()
    p = DimensionlessParams()
    reuse.build_scene("I", p, Uniform(-2.0), 6)  # cached: a bad value must still be refused
    with pytest.raises(ValueError, match="fingers"):
        reuse.build_scene("I", p, Uniform(-2.0), 6, fingers=3)
    with pytest.raises(ValueError, match="r_tip"):
        reuse.build_scene("I", p, Uniform(-2.0), 6, r_tip=-1.0)
    with pytest.raises(ValueError, match="initial_angles"):
        reuse.build_scene("I", p, Uniform(-2.0), 6, initial_angles=[0.0])
    with pytest.raises(ValueError, match="params"):
        reuse.build_scene("I", {"D": 1.0}, Uniform(-2.0), 6)
    with pytest.raises(ValueError, match="b must exceed"):
        reuse.build_scene("I", dataclasses.replace(p, b=1e-3), Uniform(-2.0), 6)
    gripper_reuse.build_gripper("I", p, Uniform(-2.0), 6, fingers=3, workpiece="cylinder")
    narrow = dataclasses.replace(p, b=0.0045)  # K = 3 tip spheres overlap on the circle of diameter b
    for build in (build_gripper, gripper_reuse.build_gripper):
        with pytest.raises(ValueError, match="fingers = 3"):
            build("I", narrow, Uniform(-2.0), 6, fingers=3, workpiece="cylinder")
    assert math.isfinite(reuse.build_scene("I", p, Uniform(-2.0), 6).model.stat.meaninertia)


def test_a_keyword_no_test_compares_is_built_fresh():
    """A builder keyword outside VERIFIED_KEYWORDS (one added later) never gets a cached scene off its default."""

    def builder(grip, params, profile, n_links, *, fingers=1, contact=None, initial_angles=None):
        raise AssertionError("not called")

    skip = ("grip", "params", "profile", "n_links", "initial_angles")
    args = ("I", DimensionlessParams(), Uniform(-1.0), 6)
    assert reuse._structure(builder, args, {"fingers": 2}, skip) is not None
    assert reuse._structure(builder, args, {"contact": None}, skip) is not None  # at its default: cached
    assert reuse._structure(builder, args, {"contact": "full"}, skip) is None


def test_a_reused_scene_has_no_stale_spec_and_an_interrupted_one_is_dropped(monkeypatch):
    reuse.clear()
    p = DimensionlessParams()
    a = reuse.build_scene("I", p, Uniform(-2.0), 6)
    assert a.spec is not None  # freshly built: the spec is the model's
    assert reuse.build_scene("I", p, Uniform(-3.0), 6).spec is None  # set in place: the spec would be stale

    def interrupted(*args, **kw):
        raise KeyboardInterrupt

    with monkeypatch.context() as mp:
        mp.setattr(reuse, "_set_links", interrupted)
        with pytest.raises(KeyboardInterrupt):
            reuse.build_scene("I", p, Uniform(-4.0), 6)
    b = reuse.build_scene("I", p, Uniform(-4.0), 6)
    assert b is not a  # the half-set scene was dropped, this one is fresh
    assert_same_model(b.model, build_scene("I", p, Uniform(-4.0), 6).model)


def test_call_settle_ratio_reports_the_repeated_call():
    from simgrip.harness.bench_reuse import call_settle_ratio

    r = call_settle_ratio("I", 6, calls=2)
    assert r["calls"] == 2 and r["links"] == 6
    assert 0.0 < r["settle_s"] <= r["call_s"] and r["ratio"] == r["call_s"] / r["settle_s"]
    assert reuse.cache_info()["hits"] == 2  # one compile, then set in place
    with pytest.raises(ValueError, match="calls"):
        call_settle_ratio("I", 6, calls=0)


@pytest.mark.parametrize("grip,kw", [("I", {"free_workpiece": False}), ("III", {"free_workpiece": False}),
                                     ("III", {"render": True, "fingers": 2}), ("II", {"render": True})])
def test_planar_reuse_fixed_workpiece_and_dressing(grip, kw):
    """A fixed workpiece (its body placed, no joints) and the rendering dressing (palm, floor plane, camera;
    the spec's stat.center/extent kept) reused as built fresh."""
    reuse.clear()
    rng = np.random.default_rng(1999)
    for _ in range(3):
        p = DimensionlessParams(D=float(rng.uniform(0.5, 2.0)), M=float(rng.uniform(0.0, 3.0)), b=0.6, gamma=0.8,
                                mu_s=float(rng.uniform(0.5, 2.0)))
        prof = Uniform(float(rng.uniform(-3.0, -1.0)))
        used, fresh = reuse.build_scene(grip, p, prof, 12, **kw), build_scene(grip, p, prof, 12, **kw)
        assert_same_model(used.model, fresh.model)
        assert_same_data(used.data, fresh.data, fresh.model)
        scribble(used)
    assert reuse.cache_info()["hits"] == 2


@pytest.mark.parametrize("grip,kappa,method,kw", [
    ("free", -3.0, "newton", {}), ("I", -5.5, "newton", {}), ("I", -5.5, "dynamics", {}), ("II", 3.0, "newton", {}),
    ("III", -4.0, "newton", {}), ("III", -4.0, "dynamics", {}), ("I", -10.0, None, {"contact": "full"})])
def test_a_cached_scene_started_without_forward_settles_bit_identically(grip, kappa, method, kw):
    """``forward=False`` (what ``simulate`` asks for): the cached scene's start angles are set without
    ``mj_forward``; every settle path computes what it reads, so the settled state equals a fresh build's
    bit for bit (was: the build's forward was 0.6 ms of a 2.6 ms call at 256 links, discarded by the settle)."""
    p = DimensionlessParams(D=1.0, M=5.0, b=0.6, mu_s=1.0, gamma=0.8)
    reuse.clear()
    reuse.build_scene(grip, p, Uniform(kappa * 0.9), 16, **kw)  # the structure cached, other parameters
    used = reuse.build_scene(grip, p, Uniform(kappa), 16, forward=False, **kw)
    assert reuse.cache_info()["hits"] >= (0 if kw else 1)  # a full-contact scene is built fresh (not cached)
    fresh = build_scene(grip, p, Uniform(kappa), 16, **kw)
    skw = {} if method is None else {"method": method}
    assert_same_state(settle(used, **skw), settle(fresh, **skw))
