"""Print the engine list a scene gives for a stage, without running it.

python3 tools/show_engines.py <scene.json> <stage>
Prints one line: ENGINES <json list of engine names> (see engines.describe).
"""
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(sys.argv[0]))), "yade_scripts"))

import yadelib  # noqa: E402

yadelib.run_under_yade_interpreter()  # YADE as a library: no remote servers (docs/scene.md)
yadelib.import_yade()

import scene as scenemod  # noqa: E402

scene, _ = scenemod.load(sys.argv[1], sys.argv[2])
import engines  # noqa: E402

wall = "pass" if sys.argv[2] == "sinusoidal" else None
print("ENGINES " + json.dumps(engines.describe(engines.build(scene, 100, "pass", wall, 10))), flush=True)
