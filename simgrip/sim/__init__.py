"""The MuJoCo model of the fingers and the workpiece, built with MjSpec (no solvers here).

========================  ==============================================================
``fingers``               ``add_fingers`` (the hinge chains) and ``FingerIndex`` (their addresses)
``workpiece``             the box: placement against the fingers, hold, place, lower, pose, slip
``contacts``              explicit contact pairs and the forces they carry
``scene``                 ``Scene``, ``build_scene``, ``set_curvature``, ``set_joint_angles``, ``finger_state``
``checks``                MuJoCo warnings and non-finite states as errors (``check_invalid_state``); where warnings go
``gl``                    the offscreen OpenGL backend (EGL, then OSMesa, on a headless machine)
========================  ==============================================================

The K-finger gripper's scene (``build_gripper``) is :mod:`simgrip.gripper.scene`.
"""
