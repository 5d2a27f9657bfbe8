"""Issue 16 §6: a K-finger finger curled away from its grip answers "not held, wrong grip", never a SettleError.

``simulate I --kappa 5 --fingers 3`` and ``simulate II --kappa -5 --fingers 4 --workpiece box`` failed with
"symmetric settle did not converge": the planar Newton settle found the contact equilibrium in the other
grip's shape (the finger presses on the workpiece from the other side of the palm), reported it not held
(``check_grip_shape``), and the skip replicated that loaded shape with the workpiece parked, so the hinge rows
kept the workpiece's weight as residual.  The skip now replicates the mechanical state and reports it not held
with the wrong-grip warning, as the dynamics does; and under method "auto" a failing skip falls back to the
dynamics with a warning saying so.
"""

from __future__ import annotations

import pytest

from simgrip import STANDARD, Uniform
from simgrip.cli import main
from simgrip.settle import SettleError
from simgrip.gripper.settle import settle_gripper
from simgrip.gripper.scene import build_gripper

# (grip, kappa, K, workpiece): the two reproductions and the other finger counts and workpieces
WRONG_WAY = [("I", 5.0, 3, "cylinder"), ("II", -5.0, 4, "box"), ("I", 5.0, 2, "box"), ("II", -5.0, 3, "sphere")]


def _scene(grip, kappa, K, workpiece, n=16):
    return build_gripper(grip, STANDARD, Uniform(kappa), n, fingers=K, workpiece=workpiece)


@pytest.mark.parametrize("grip, kappa, K, workpiece", WRONG_WAY)
def test_wrong_way_curl_is_not_held_by_every_method(grip, kappa, K, workpiece):
    auto = settle_gripper(_scene(grip, kappa, K, workpiece))
    assert auto.method == "symmetric" and auto.converged
    assert not auto.held and not auto.grip_matched
    assert sum(w.startswith("wrong grip:") for w in auto.warnings) == 1  # the planar one is not repeated
    assert not any("symmetry skip failed" in w for w in auto.warnings)
    other = "II" if grip == "I" else "I"
    assert f"in Grip {other}'s shape" in auto.warnings[0]
    # the residual is the K-finger balance of the replicated loaded shape, within its tolerance
    assert auto.residual <= auto.tolerance
    if workpiece != "sphere":  # the K-finger dynamics (Grips I/II) gives the same verdict
        dyn = settle_gripper(_scene(grip, kappa, K, workpiece), method="dynamics")
        assert not dyn.held and not dyn.grip_matched and dyn.converged
        assert any(w.startswith("wrong grip:") for w in dyn.warnings)


def test_cli_reproductions_exit_0_not_held(capsys):
    import json

    for argv in (["simulate", "I", "--kappa", "5", "--fingers", "3", "--links", "16", "--json"],
                 ["simulate", "II", "--kappa", "-5", "--fingers", "4", "--workpiece", "box", "--links", "16",
                  "--json"]):
        assert main(argv) == 0
        rec = json.loads(capsys.readouterr().out)
        assert rec["feasible"] is False and rec["held"] is False and rec["method"] == "symmetric"
        assert rec["warnings"] and rec["warnings"][0].startswith("wrong grip:")


def _cradle(params, n):
    """The K = 4 cradle (Grip III, box) started where the theory is, as :func:`simgrip.gripper.simulate_gripper`."""
    from simgrip.scenes import start_angles

    return build_gripper("III", params, Uniform(-4.0), n, fingers=4, workpiece="box",
                         initial_angles=start_angles("III", params, Uniform(-4.0), n))


def _failing_skip(monkeypatch):
    """Inject a skip failure (the planar Newton's SettleError) to test the fallback; the planar dynamics (the
    cradle's fallback) still runs."""
    import simgrip.gripper.symmetry as gs

    real = gs._settle_exact

    def fail(*a, **k):
        if k.get("planar_method", "newton") == "newton":
            raise SettleError("symmetric settle did not converge (injected)")
        return real(*a, **k)

    monkeypatch.setattr(gs, "_settle_exact", fail)


def test_auto_falls_back_to_the_dynamics_with_a_warning(monkeypatch):
    _failing_skip(monkeypatch)
    st = settle_gripper(_scene("I", -5.0, 3, "cylinder"))
    assert st.method == "dynamics" and st.converged and st.held
    assert "symmetry skip failed (symmetric settle did not converge (injected))" in st.warnings[0]
    assert "settled by the over-damped dynamics instead" in st.warnings[0]
    # the same with the surface contact, which the dynamics has
    assert settle_gripper(_scene("I", -5.0, 3, "cylinder"), contact="surface").method == "dynamics"
    # the cradle (no K-finger dynamics): one finger's planar dynamics, replicated; from the theory's start (as
    # simulate_gripper starts it) it holds as the skip does
    cradle = settle_gripper(_cradle(STANDARD, 16))
    assert cradle.method == "dynamics" and cradle.contact == "surface" and cradle.held and cradle.converged
    assert "planar dynamics, replicated" in cradle.warnings[0]


def test_no_fallback_where_the_dynamics_cannot_answer_the_question(monkeypatch):
    _failing_skip(monkeypatch)
    sc = _scene("I", -5.0, 3, "cylinder")
    with pytest.raises(SettleError, match="injected"):  # the method asked for explicitly
        settle_gripper(sc, method="symmetric")
    with pytest.raises(SettleError, match="injected"):  # the point contact is the skip's only
        settle_gripper(sc, contact="point")


@pytest.mark.parametrize("D, mu_s", [(1.0, 0.0), (1e-2, 100.0)])
def test_cradle_skip_failures_at_the_box_edges_are_answered(D, mu_s):
    # issue 16 audit: the cradle's planar Newton stalls at M = 0 with D = 1e-2 ("settle did not
    # converge"); the default answers by the planar dynamics, replicated, with the warning
    from simgrip.params import DimensionlessParams

    st = settle_gripper(_cradle(DimensionlessParams(D=D, M=0.0, mu_s=mu_s, b=0.6), 32))
    assert st.converged and st.residual <= st.tolerance
    assert st.method == "symmetric" or "symmetry skip failed" in st.warnings[0]


def test_unconverged_skip_falls_back_under_allow_unconverged():
    # a Newton budget of 1 iteration leaves the skip unconverged; the dynamics' own budget (max_steps is the
    # physics steps there, default GRIPPER_MAX_STEPS when not given) is not reachable from one argument, so
    # the fallback keeps the given budget and, unconverged too, the skip's state is returned
    sc = _scene("I", -5.0, 3, "cylinder")
    st = settle_gripper(sc, max_steps=1, allow_unconverged=True)
    assert st.method == "symmetric" and not st.converged
    with pytest.raises(SettleError, match="fallback to the dynamics failed too"):
        settle_gripper(sc, max_steps=1)


# (Grip II at D = 1e-2 cannot hold at all: the soft finger sags below the palm, N < 0 in the BVP too)
@pytest.mark.parametrize("grip, kappa, K, workpiece, D", [
    ("I", -6.0, 3, "cylinder", 1e-2), ("I", -6.0, 3, "cylinder", 1.0), ("I", -6.0, 3, "cylinder", 1e4),
    ("I", -6.0, 2, "box", 1.0), ("II", 6.0, 4, "box", 1.0), ("II", 6.0, 4, "box", 1e4)])
def test_weightless_workpiece_is_held_by_both_methods(grip, kappa, K, workpiece, D):
    # M = 0 is accepted; the K-finger model failed to compile (MuJoCo: "mass and inertia of moving bodies must be
    # larger than mjMINVAL") and, with a 1e-12 mass, the dynamics dropped it (MuJoCo's soft contact sinks without
    # bound under a massless body).  The inertia is floored, the weight stays 0 (GripperScene.weight_relief).
    from simgrip.params import DimensionlessParams

    p = DimensionlessParams(D=D, M=0.0, mu_s=1.0, b=0.6)
    for method in ("symmetric", "dynamics"):
        sc = build_gripper(grip, p, Uniform(kappa), 16, fingers=K, workpiece=workpiece)
        st = settle_gripper(sc, method=method)
        assert st.held and st.converged, (method, st.warnings)
        # the contacts carry no weight: the vertical forces on the fingers vanish to the settle's tolerance
        assert max(abs(r.N2) for r in st.records) <= st.tolerance, method
        assert abs(st.force_balance[2]) <= K * st.tolerance, method


def test_weight_relief_keeps_the_true_weight():
    from simgrip.params import DimensionlessParams

    heavy = build_gripper("I", STANDARD, Uniform(-6.0), 16, fingers=3, workpiece="cylinder")
    assert heavy.weight_relief == 0.0  # M = 5 is above the floor: the model's mass is the workpiece's
    light = build_gripper("I", DimensionlessParams(M=0.0), Uniform(-6.0), 16, fingers=3, workpiece="cylinder")
    assert light.workpiece_mass == 0.0
    assert light.weight_relief == pytest.approx(float(light.model.body_mass[light.workpiece_body]) * light.physical.g,
                                                rel=1e-12)
    assert light.weight_relief > 0.0


def test_a_finger_that_does_not_reach_says_so():
    # issue 16 audit: kappa = -1 curls too little to bring the tip back to the face (free tip at X = 0.78 l);
    # both methods drop it, the BVP (tip prescribed on the face) finds the finger pulled onto it by a heavy
    # workpiece and calls it feasible: the dropped states say why they may differ
    from simgrip.params import DimensionlessParams

    p = DimensionlessParams(D=1.0, M=1e4, mu_s=100.0, b=0.6)
    for method in ("auto", "dynamics"):
        st = settle_gripper(build_gripper("I", p, Uniform(-1.0), 16, fingers=3, workpiece="cylinder"), method=method)
        assert not st.held and st.converged
        assert any(w.startswith("not held: finger 0's free shape has its tip at X = 0.78") for w in st.warnings)
    held = settle_gripper(_scene("I", -6.0, 3, "cylinder"))  # a finger that reaches: no such warning
    assert held.held and not held.warnings


def test_frictionless_vertical_faces_drop_without_stepping():
    # issue 16 audit: D = 1e4, mu_s = 0 ran the K-finger dynamics out of its step budget (SettleError)
    from simgrip.params import DimensionlessParams

    p = DimensionlessParams(D=1e4, M=5.0, mu_s=0.0, b=0.6)
    for K, workpiece in ((3, "cylinder"), (2, "box")):
        st = settle_gripper(build_gripper("I", p, Uniform(-6.0), 16, fingers=K, workpiece=workpiece),
                            method="dynamics")
        assert not st.held and st.converged
        assert st.method == "dynamics"
    skip = settle_gripper(build_gripper("I", p, Uniform(-6.0), 16, fingers=3, workpiece="cylinder"))
    assert not skip.held  # the Newton skip agrees


def test_holds_at_the_friction_cone_say_so():
    from simgrip.params import DimensionlessParams
    from simgrip.gripper.state import FRICTION_MARGIN

    need = settle_gripper(_scene("I", -6.0, 3, "cylinder")).records[0].required_mu
    edge = settle_gripper(build_gripper("I", STANDARD.replace(mu_s=need * (1 + FRICTION_MARGIN / 2)), Uniform(-6.0),
                                        16, fingers=3, workpiece="cylinder"))
    assert edge.held and any("friction cone's edge" in w for w in edge.warnings)
    inside = settle_gripper(build_gripper("I", STANDARD.replace(mu_s=need * (1 + 3 * FRICTION_MARGIN)),
                                          Uniform(-6.0), 16, fingers=3, workpiece="cylinder"))
    assert inside.held and not inside.warnings
    # issue 16 audit: the cradle's Newton holds a weightless box at D = 1 with mu_s = 1, its corner contact
    # saturated in MuJoCo's frame while the rod's frame at gamma needs mu = 1.11 (the BVP: infeasible)
    st = settle_gripper(_cradle(DimensionlessParams(D=1.0, M=0.0, mu_s=1.0, b=0.6), 32))
    assert st.held and st.records[0].required_mu > 1.0
    assert any("friction cone's edge" in w for w in st.warnings)


def test_the_cradle_says_each_warning_once():
    """The replicated planar state's warnings and the K-finger's own overlapped (M = 0 with mu_s = 0 twice)."""
    from simgrip.cli import main
    import json

    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["simulate", "III", "--kappa", "-4", "--fingers", "4", "--workpiece", "box", "--M", "0",
                     "--mu", "0", "--links", "16", "--json"]) == 0
    warnings = json.loads(buf.getvalue())["warnings"]
    assert any(w.startswith("M = 0 with mu_s = 0") for w in warnings)
    assert len(warnings) == len(set(warnings))
