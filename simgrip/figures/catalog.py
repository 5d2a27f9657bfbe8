"""Which figures exist, their names, and the per-grip conventions the data and the plots share."""

from __future__ import annotations

__all__ = ["FIGURES", "GRIPPER_FIGURES", "RENDERED_FIGURES", "figure_key"]

#: Figure names, in the paper's order, with a one-line description.
FIGURES = {
    "fig06": "free clamped rod with uniform intrinsic curvature, without and with gravity",
    "fig07": "Grip I (palm down) vs kappa_bar0 in [0, -6]",
    "fig08": "Grip II (palm up) vs kappa_bar0 in [0, 6]",
    "fig09": "Grip III (cradle, gamma = 0.8) vs kappa_bar0 in [0, -10]",
    "fig11": "smallest eigenvalue of E^T L E along the sweeps of Figs. 7-9",
    "fig12": "concentrated profile (34), kappa_max = 6: profile and free heavy rod",
    "fig13": "Grip I with profile (34), alpha in [1, 3]",
    "fig14": "Grip II with profile (34), alpha in [1, 3]",
    "fig15": "Grip III with profile (34), alpha in [1, 3]",
    "fig16": "least mu_s for M = 5 and largest M at mu_s = 1, three grips",
    # K-finger grippers (simgrip.figures.gripper), Grip I at the standard case
    "grasp3": "three fingers around a cylinder, settled at n = 32 (MuJoCo rendering)",
    "grasp4": "four fingers around a box, settled at n = 32 (MuJoCo rendering)",
    "grip_forces": "normal force per finger vs kappa_bar0, cylinder with 3 and 4 fingers: simulation on the BVP",
    # past the onset of full contact (simgrip.figures.full_contact)
    "fig07_full": "Grip I N and tip vs kappa_bar0 in [0, -12]: point contact (invalid past the onset), "
                  "free-boundary reference, MuJoCo contact='full' at n = 32",
    "fig07_wrap": "free rod wrapping a fixed cylinder vs kappa_bar0 in [-7, -12]: the free rod (invalid through it), "
                  "the wrap BVP, the constrained chain at n = 32",
    # a wrap grasp (simgrip.figures.wrap_grasp)
    "wrap_grasp": "three fingers wrapping a sphere, contact='full', settled at n = 32 (MuJoCo rendering)",
}

#: Figures made by :mod:`simgrip.figures.gripper`, and those of them that need OpenGL (rendered pictures).
GRIPPER_FIGURES = ("grasp3", "grasp4", "grip_forces")
RENDERED_FIGURES = ("grasp3", "grasp4", "wrap_grasp")

#: Figures made by :mod:`simgrip.figures.full_contact`.
FULL_CONTACT_FIGURES = ("fig07_full", "fig07_wrap")

#: Rough relative cost of computing each figure (the slow ones are started first).
COST = {"fig16": 10, "fig11": 8, "fig15": 6, "fig13": 4, "fig14": 4, "fig09": 3,
        "fig07": 2, "fig08": 2, "fig06": 2, "fig12": 1, "grip_forces": 2, "grasp3": 1, "grasp4": 1,
        "fig07_full": 4, "fig07_wrap": 3, "wrap_grasp": 1}

#: Figures that can carry the MuJoCo overlay, and the grip of each grip sweep.
OVERLAY_FIGURES = ("fig06", "fig07", "fig08", "fig09")
FIG_GRIP = {"fig07": "I", "fig08": "II", "fig09": "III"}

#: Sign of the curvature that curls each grip's finger towards the workpiece (profile (34)'s ``p``).
GRIP_SIGN = {"I": -1, "II": 1, "III": -1}
GRIP_TITLE = {"I": "Grip I (palm down)", "II": "Grip II (palm up)", "III": "Grip III (cradle)"}


def figure_key(name) -> str:
    """Normalise ``6``, ``"6"``, ``"fig6"``, ``"fig06"`` to ``"fig06"`` (other names as listed); ``ValueError`` for an unknown figure."""
    s = str(name).strip().lower()
    if s in FIGURES:
        return s
    if s.startswith("fig"):
        s = s[3:]
    try:
        key = f"fig{int(s):02d}"
    except ValueError:
        key = None
    if key not in FIGURES:
        raise ValueError(f"unknown figure {name!r}; known: {', '.join(FIGURES)}")
    return key
