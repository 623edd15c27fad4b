"""The eight recipes of docs/EXTENDING.md, run as written there, each in a fresh interpreter from
outside the package: a new load type, a new element, a new applied field, a new benchmark case,
a new obstacle shape, a new material law, a new support kind and a new design variable, each
through the public extension points only (its checks are the recipe's own assertions: exact
solutions, convergence rates, finite-difference tangents).  Recipes 5 to 8 are plugin files: each
runs a scenario that names the file itself in ``plugins`` through the command line."""
import os
import re
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOC = os.path.join(ROOT, "docs", "EXTENDING.md")


def _recipes():
    text = open(DOC, encoding="utf-8").read()
    parts = re.split(r"^## (Recipe \d+[^\n]*)\n", text, flags=re.M)[1:]
    out = {}
    for title, body in zip(parts[::2], parts[1::2]):
        blocks = re.findall(r"```python\n(.*?)```", body, flags=re.S)
        out[title.split(":")[0]] = "\n".join(blocks)
    return out


RECIPES = _recipes()


def test_the_document_has_eight_recipes():
    assert sorted(RECIPES) == [f"Recipe {i}" for i in range(1, 9)]
    assert all("register" in code or "add_case" in code for code in RECIPES.values())
    assert all("core_se3" in code and "assert" in code for code in RECIPES.values())
    for i in range(5, 9):                 # plugins used from a scenario file through the command line
        code = RECIPES[f"Recipe {i}"]
        assert "plugins = [" in code and '"-m", "core_se3"' in code and 'if __name__ == "__main__":' in code


@pytest.mark.parametrize("name", sorted(RECIPES))
def test_recipe_runs_from_outside_the_package(name, tmp_path):
    script = tmp_path / "recipe.py"
    script.write_text(RECIPES[name])
    r = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, f"{name} failed:\n{r.stdout[-2000:]}\n{r.stderr[-4000:]}"
