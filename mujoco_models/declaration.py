"""MuJoCo's declaration to the engine registry (analytic.engine.declaration; read by
compare.runs.backends): plain data, no MuJoCo imported."""

from treeimpact.analytic.engine.declaration import EngineDeclaration

DECLARATION = EngineDeclaration(
    name="mujoco", label="MuJoCo",
    description="MuJoCo (MJCF) slide-joint or hinged-segment trunk",
    # MuJoCo's physics comes as mujoco-core (pyproject.toml); mujoco only adds a viewer
    package="mujoco", distributions=("mujoco-core", "mujoco"),
    run_cost=(("sdof", 0.05), ("chain", 0.5), ("flex", 0.5)),
    variants=("integrator", ("Euler", "implicit", "implicitfast", "RK4")),
    shades=("#1f77b4", "#4f9fd6", "#8cc3ea", "#0b3d75"))
