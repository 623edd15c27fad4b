"""Run the three examples and keep their pictures for the README: docs/pictures/NAME.png.

    python examples/pictures.py [OUTROOT]          (default out/; ~1 min)

Each example runs as ``core-se3 run examples/NAME.toml --out OUTROOT/NAME --force`` would; its
``shell.png`` is copied, reduced to a 256-colour palette (a few tens of kB), to docs/pictures.
"""
import os
import sys

from PIL import Image

from core_se3 import scenario
from core_se3.scenario import runner

HERE = os.path.dirname(os.path.abspath(__file__))
PICTURES = os.path.join(os.path.dirname(HERE), "docs", "pictures")
EXAMPLES = ("gripper", "rotating-field", "hanging-plate")


def main(root="out"):
    os.makedirs(PICTURES, exist_ok=True)
    for name in EXAMPLES:
        res = runner.run(scenario.load(os.path.join(HERE, name + ".toml")), out=os.path.join(root, name),
                         force=True)
        target = os.path.join(PICTURES, name + ".png")
        Image.open(res.files["picture"]).convert("RGB").quantize(256).save(target, optimize=True)
        tip = {k: [round(x, 3) for x in v["u"]] for k, v in res.doc["steps"][-1]["probes"].items()}
        print(f"{name}: {len(res.doc['steps']) - 1} steps, {res.doc['timings']['total']:.1f} s, probes {tip} "
              f"-> {target} ({os.path.getsize(target) // 1024} kB)")


if __name__ == "__main__":
    main(*sys.argv[1:])
