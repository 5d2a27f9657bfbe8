"""The K-finger gripper in one place: K fingers around a palm axis holding a box, cylinder or sphere free in 3-D.

The public entry is :func:`simulate_gripper` (build, settle, return the
:class:`~simgrip.gripper.state.GripperState`), :func:`gripper_record` (its
flat record) and :func:`compare_gripper` (the settled gripper next to the
planar BVP).  The modules follow the one-way flow parameters → scene → settle
→ state → comparison; a module only imports those before it in this list:

====================  ==================================================================================
``placement``         where each finger meets an off-centre or turned workpiece (reach, normal)
``model``             ``GripperScene``, ``compile_gripper``, the fingers' azimuths (both builders')
``cradle``            Grip III with four fingers under a box's bottom edges (the scene)
``scene``             ``build_gripper``: the K fingers, the palm, the workpiece
``scene_symmetry``    whether a built scene is exactly symmetric, read from its compiled model
``reuse``             ``build_gripper`` compiled once per structure, set in place (:mod:`simgrip.sim.reuse`)
``state``             ``GripperState``, ``FingerRecord`` and their reading from MuJoCo
``rest_depth``        how deep the soft contact rests under a normal force in the dynamics
``start``             the settle's start: the balanced shares, the rest depth, the chain per finger
``dynamics``          the over-damped K-finger dynamics (``GripperDynamics``, one settle run)
``stability``         whether the balanced start is a stable rest (the statics' second variation)
``full``              the full-contact settle (every link touches) at a box depth
``symmetry``          the symmetry skip: one finger's planar settle where the scene is exactly symmetric
``settle``            ``settle_gripper``: the symmetry skip where exact, else the dynamics
``simulate``          ``simulate_gripper``, ``gripper_record``, ``gripper_nodes`` (end to end)
``compare``           ``compare_gripper``: the settled gripper next to the elastica reference
====================  ==================================================================================

The scene modules (``placement`` to ``reuse``) never import a settle
module; ``tests/test_import_graph.py`` checks that, the order above and that
no modules import each other.
"""

from __future__ import annotations

from simgrip.gripper.compare import compare_gripper
from simgrip.gripper.simulate import gripper_nodes, gripper_record, simulate_gripper

__all__ = ["compare_gripper", "gripper_nodes", "gripper_record", "simulate_gripper"]
