"""The MuJoCo model of the fingers and the workpiece (built with MjSpec; no solvers here)."""
