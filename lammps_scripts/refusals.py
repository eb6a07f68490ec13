"""What the lammps engine does not run, named by key: the stage refuses it (exit 2), and the
pre-flight check refuses a config that asks for it (preflight/checks.py, before any job).

Pure Python. Each refusal names the scene key, its value and what is supported. Every stage
runs (pack, preshear, heaviside, sinusoidal and every reversal schedule or train); what is
refused is a setting of the scene.
"""


def refusals(scene, stage=None):
    """The reasons the lammps engine cannot run ``scene``, one sentence each; [] if none.

    Parameters
    ----------
    scene : dict
        A validated scene (yade_scripts/scene.validate).
    stage : str, optional
        The stage asked for (pack, preshear, heaviside, sinusoidal or a schedule's name): every
        stage runs, so it refuses nothing by itself (kept so that a stage could be refused by name).
    """
    out = []
    kind = scene.get("cell", {}).get("kind", "walls")
    if kind != "walls":
        out.append(f"cell.kind = {kind!r} (supported: walls; the periodic cell runs in yade only: LAMMPS's "
                   f"sheared periodic box with a pressure-controlled height is not set up here)")
    fx = scene.get("effects", {})
    if fx.get("gravity"):
        out.append(f"effects.gravity = {fx['gravity']!r} (supported: false)")
    if fx.get("damping", 0.0) != 0.0:
        out.append(f"effects.damping = {fx['damping']!r} (supported: 0; LAMMPS 2021 has no Cundall damping)")
    if fx.get("rolling_resistance", 0.0) != 0.0:
        out.append(f"effects.rolling_resistance = {fx['rolling_resistance']!r} (supported: 0)")
    return out
