"""PyBullet's declaration to the engine registry (analytic.engine.declaration; read by
compare.runs.backends): plain data, no PyBullet imported."""

from treeimpact.analytic.engine.declaration import EngineDeclaration

DECLARATION = EngineDeclaration(
    name="bullet", label="Bullet", description="PyBullet prismatic or hinged-link trunk",
    package="pybullet", distributions=("pybullet",),
    run_cost=(("sdof", 0.15), ("chain", 2.5)), variants=("contact", ("soft", "newton")),
    shades=("#d95f02", "#f28e2b", "#f7b76d"))
