"""What README.md and docs/*.md state about the command line and the defaults, read from their
text and compared with the code, so that a renamed flag or a changed default fails here instead
of misleading a user who reads the docs first.

* every ``core-se3 ...`` command line of the docs (fenced blocks and inline code) names a
  subcommand and only flags its parser accepts; the concrete ones (no placeholder) parse, name a
  catalogue case that exists and an example file that exists;
* the defaults the prose states: the switches table of docs/STEPS.md (``NewtonOptions``), the
  arc-length keys of docs/SCENARIOS.md (``[solver]``), the signature of ``arc_length`` in
  docs/PATHFOLLOWING.md, the options of docs/CONTROL.md (``ControlOptions``), the contact law of
  docs/CONTACT.md (``ContactLaw``), the constants README.md quotes, the start costs of the 'auto'
  backend docs/SCENARIOS.md states, and every constant quoted as ```NAME` = value``;
* every exception and warning class the docs name exists;
* the keys docs/SCENARIOS.md says a resume may change (the fingerprint's ``NON_PHYSICAL``);
* the Python fragments of README.md, docs/CONTACT.md, docs/CONTROL.md, docs/PATHFOLLOWING.md and
  docs/SCENARIOS.md run as written and give what their comments say (docs/EXTENDING.md's run in
  tests/test_extending.py; docs/DESIGN.md's are sketches on names they do not define).

The scenario schema's own tables are generated and checked by tests/test_kind_contracts.py."""
import argparse
import dataclasses
import glob
import os
import re
import shlex

import numpy as np
import pytest

from core_se3.catalogue import CASES
from core_se3.cli import parser
from core_se3.control import ControlOptions
from core_se3.model.contact_law import ContactLaw
from core_se3.scenario import NON_PHYSICAL
from core_se3.scenario.schema import ARCLENGTH
from core_se3.solvers import ArcLengthOptions, NewtonOptions

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOCS = ["README.md"] + sorted(os.path.relpath(p, ROOT) for p in glob.glob(os.path.join(ROOT, "docs", "*.md")))
# a placeholder makes a command a synopsis (checked for its flags only), not one to parse
PLACEHOLDER = re.compile(r"\.\.\.|…|\$|\[-|\b[A-Z]{3,}\b|NXxNY")
# catalogue cases that a doc defines itself before it runs them (docs/EXTENDING.md's recipe)
DOC_CASES = {"rollup-wide"}


def read(path):
    with open(os.path.join(ROOT, path), encoding="utf-8") as fh:
        return fh.read()


def doc_commands(text):
    """The ``core-se3`` command lines of a Markdown text: every line of its fenced blocks other
    than Python and TOML, and every inline code span, from the word after ``core-se3`` on
    (a trailing ``# comment`` cut off)."""
    fence = re.compile(r"^```(\w*)\n(.*?)^```$", flags=re.S | re.M)
    spans = [line for lang, body in fence.findall(text) if lang not in ("python", "toml")
             for line in body.splitlines()]
    spans += [s.replace("\n", " ") for s in re.findall(r"`([^`]+)`", fence.sub("", text))]
    found = (re.search(r"(?:^|[\s/])core-se3 (.*)", s) for s in spans)
    return [m.group(1).split(" #")[0].strip() for m in found if m]


def subparser(words):
    """(the parser of the subcommand that ``words`` start with, the words after it), or None
    when the first word is no subcommand (prose such as 'core-se3 did not write ...')."""
    p, top = parser(), True
    while True:
        sub = [a for a in p._actions if isinstance(a, argparse._SubParsersAction)]
        if not sub or not words or words[0] not in sub[0].choices:
            return None if top else (p, words)
        p, words, top = sub[0].choices[words[0]], words[1:], False


def command_problems(command):
    """What is wrong with one documented command line: a flag its subcommand does not take, and
    for a concrete line, a parse error, an unknown case or a missing example file."""
    words = shlex.split(command.replace("[", " ").replace("]", " ").replace("|", " ")) \
        if PLACEHOLDER.search(command) else shlex.split(command)
    found = subparser(words)
    if found is None:
        return []
    p, rest = found
    flags = {s for a in p._actions for s in a.option_strings}
    bad = [f"{w!r} is no option of 'core-se3 {command.split(' --')[0]}'" for w in rest
           if w.startswith("-") and w.split("=")[0] not in flags]
    if bad or PLACEHOLDER.search(command) or not rest or rest[0].startswith("-"):
        return bad                     # a synopsis, or a mention such as `core-se3 bench run --json`
    try:
        args = parser().parse_args(shlex.split(command))
    except SystemExit:
        return [f"'core-se3 {command}' does not parse"]
    name = getattr(args, "name", None)
    if getattr(args, "bcmd", None) == "run" and name not in CASES and name not in DOC_CASES:
        bad.append(f"no catalogue case {name!r}")
    path = getattr(args, "scenario", None)
    if path and path.startswith("examples/") and not os.path.exists(os.path.join(ROOT, path)):
        bad.append(f"no file {path}")
    return bad


@pytest.mark.parametrize("path", DOCS)
def test_every_documented_command_line_is_one_the_cli_accepts(path):
    commands = doc_commands(read(path))
    problems = [f"{path}: {p}" for c in commands for p in command_problems(c)]
    assert not problems, problems


def test_the_command_check_fails_on_a_wrong_flag_a_wrong_case_and_a_missing_file():
    """The check above can fail: a flag of another subcommand, a misspelt case, a file that is
    not there, a flag in a synopsis."""
    assert command_problems("bench run cantilever-shear --out x")
    assert command_problems("bench run cantilever-sheer")
    assert command_problems("run examples/no-such.toml --out out/x")
    assert command_problems("check-mesh SCENARIO.toml [--levels N] [--tolerance T]")
    assert not command_problems("bench run cantilever-shear --plot out/a.png --json out/a.json")
    assert not command_problems("check-mesh SCENARIO.toml [--levels N] [--tol T]")


def doc_value(text):
    """A default as the docs write it: true/false, a number (1e-3, 0.05, 8), a quoted string."""
    text = text.strip().strip("`").strip()
    if text in ("true", "false", "True", "False"):
        return text.lower() == "true"
    if text.startswith('"'):
        return text.strip('"')
    if text == "None":
        return None
    return float(text)


def same(doc, code):
    if isinstance(doc, float) and not isinstance(code, bool):
        return code is not None and np.isclose(doc, code, rtol=1e-12, atol=0.0)
    return doc == code


def defaults(cls):
    return {f.name: f.default for f in dataclasses.fields(cls)}


def test_steps_switches_table_states_newton_options_defaults():
    section = read("docs/STEPS.md").split("## Switches", 1)[1]
    rows = re.findall(r"^\| `(\w+)` \| ([^|]+) \|", section, flags=re.M)
    code = defaults(NewtonOptions)
    assert len(rows) >= 10
    wrong = [(k, v, code.get(k, "no such option")) for k, v in rows
             if k not in code or not same(doc_value(v), code[k])]
    assert not wrong, f"docs/STEPS.md 'Switches' (key, doc, code): {wrong}"
    from core_se3.scenario.schema import SOLVER
    keys = {p.name for p in SOLVER.params} | {p.name for p in ARCLENGTH.params}      # "[solver]" in its header
    assert {k for k, _ in rows} <= keys, {k for k, _ in rows} - keys


def arclength_paragraph():
    text = read("docs/SCENARIOS.md")
    return text.split('With `control = "arclength"` further keys apply:', 1)[1].split("with `critical_points`", 1)[0]


def test_scenarios_arclength_keys_state_the_schema_defaults():
    """`max_steps` (200), `psi` (0: ...), ...: the value before the first ':' / ',' / ')' of each
    key's parenthesis; `method`'s first choice is its default; `dlam0` is lam_end / steps."""
    stated = dict(re.findall(r"`(\w+)`\s+\(`?([-+\w.\"]+)", arclength_paragraph()))
    code = {p.name: p.default for p in ARCLENGTH.params}
    assert set(stated) == set(code), (set(stated) ^ set(code))
    for k, v in stated.items():
        if k == "dlam0":
            assert v == "load" and code[k] is None     # "load factor of the first predictor, default lam_end/steps"
            continue
        assert same(doc_value(v), code[k]), f"docs/SCENARIOS.md: [solver] {k} default {v}, the code's {code[k]!r}"
    assert all(same(code[k], defaults(ArcLengthOptions)[k]) for k in code if k != "dlam0")


def test_scenarios_keys_a_resume_may_change_are_the_fingerprints():
    text = read("docs/SCENARIOS.md")
    sentence = text.split("it is not part of the scenario's\nfingerprint, nor are", 1)[1].split(".", 1)[0]
    stated = set(re.findall(r"`(\w+)`", sentence)) | {"max_steps"}
    assert stated == set(NON_PHYSICAL), f"docs/SCENARIOS.md vs NON_PHYSICAL: {stated ^ set(NON_PHYSICAL)}"


def test_pathfollowing_signature_states_arc_length_defaults():
    text = read("docs/PATHFOLLOWING.md")
    sig = re.search(r"`arc_length\((.*?)\)` returns", text, flags=re.S).group(1)
    code = defaults(ArcLengthOptions)
    stated = dict(re.findall(r"(\w+)=([-\w.\"]+)", sig))
    opts = {k: v for k, v in stated.items() if k in code}
    assert {"dlam0", "method", "psi", "ds_max", "ds_max_factor", "target_iter", "stability",
            "branch_switch", "land"} <= set(opts)
    wrong = [(k, v, code[k]) for k, v in opts.items()
             if not same(doc_value(v), code[k])]
    assert not wrong, f"docs/PATHFOLLOWING.md arc_length(...) (key, doc, code): {wrong}"
    import inspect
    from core_se3.solvers import arc_length
    params = inspect.signature(arc_length).parameters
    others = set(stated) - set(code)          # arc_length's own (lam_end, stop_at, lam_min); verbose was removed
    assert others <= set(params), others
    assert all(same(doc_value(stated[k]), params[k].default) for k in others if k in ("lam_end", "lam_min"))


def test_control_options_and_defaults_are_the_documented_ones():
    text = read("docs/CONTROL.md")
    listed = re.search(r"Options\n?\s*\(`ControlOptions`, or keywords\):(.*?)\.\n", text, flags=re.S).group(1)
    code = defaults(ControlOptions)
    assert set(re.findall(r"`(\w+)`", listed)) == set(code)
    stated = dict(re.findall(r"`(\w+)`\s+\(([-\d.e]+)[ )]", text))
    stated.update(re.findall(r"`(\w+)` iterations \(default ([-\d.e]+)", text))
    tol = re.search(r"`rtol`, `dtol` \(default ([-\d.e]+)", text).group(1)
    stated.update(rtol=tol, dtol=tol)
    assert {"max_iter", "max_turn", "path_tolerance", "max_splits", "factor_cost", "rtol"} <= set(stated)
    wrong = [(k, v, code[k]) for k, v in stated.items() if not same(float(v), code[k])]
    assert not wrong, f"docs/CONTROL.md (key, doc, code): {wrong}"
    from core_se3.control.corrector import CARRY_MOVE
    assert same(doc_value(re.search(r"`CARRY_MOVE` = ([\d.e-]+)", text).group(1)), CARRY_MOVE)


def test_contact_law_defaults_are_the_documented_ones():
    text = read("docs/CONTACT.md")
    law = ContactLaw()
    assert same(doc_value(re.search(r"`soft_start`, default ([\d.e-]+)", text).group(1)), law.soft_start)
    m = re.search(r'\*\*Default: mode `"(\w+)"`, β = ([\d.]+),\s+ε = ([\d.e-]+) h, tolerance ([\d.e-]+) h\*\*', text)
    assert m, "docs/CONTACT.md: the sentence stating the contact law's defaults moved"
    assert (m.group(1), float(m.group(2))) == (law.mode, law.beta)
    eps, tol, cap = law.lengths(1.0)                     # (eps, tol, cap_depth) for h = 1
    assert same(float(m.group(3)), eps) and same(float(m.group(4)), tol)
    scen = read("docs/SCENARIOS.md")
    assert same(doc_value(re.search(r"`cap_depth` \(default ([\d.]+) h\)", scen).group(1)), cap)


def test_readme_constants_are_the_codes():
    from core_se3 import Material
    from core_se3.solvers.linalg import AUTO_MUMPS_MIN
    from core_se3.solvers.splitting import MAX_LOAD_TURN, MAX_PRESCRIBED_TURN
    text = read("README.md")
    from core_se3.scenario.mesh_check import DEFAULT_TOL
    helps = next(a.help for a in subparser(["check-mesh"])[0]._actions if "--tol" in a.option_strings)
    assert same(float(re.search(r"\(default ([\d.]+)\)", helps).group(1)), DEFAULT_TOL)
    assert same(float(re.search(r"`--tol` \((\d+) %\)", text).group(1)) / 100, DEFAULT_TOL)
    floor = float(re.search(r"`shear_stabilisation_floor` = ([\d.]+)", text).group(1))
    assert same(floor, Material(E=1.0, nu=0.0, h=0.1, shear_stabilisation=0.1).shear_stabilisation_floor)
    assert same(float(re.search(r"SciPy SuperLU below (\d+) unknowns", text).group(1)), AUTO_MUMPS_MIN)
    assert same(float(re.search(r"prescribed rotations larger than ([\d.]+)π per\s+step", text).group(1)) * np.pi,
                MAX_PRESCRIBED_TURN)
    assert re.search(r"turn by more than π/4 per step", text) and same(np.pi / 4, MAX_LOAD_TURN)


def test_a_wrong_default_in_a_doc_fails_the_comparison():
    """The comparisons above can fail: the switches table with end_check false, the arc-length
    paragraph with max_steps 100 (the code's 200)."""
    section = read("docs/STEPS.md").split("## Switches", 1)[1].replace("| `end_check` | true", "| `end_check` | false")
    rows = dict(re.findall(r"^\| `(\w+)` \| ([^|]+) \|", section, flags=re.M))
    assert not same(doc_value(rows["end_check"]), defaults(NewtonOptions)["end_check"])
    stated = dict(re.findall(r"`(\w+)`\s+\(`?([-+\w.\"]+)", arclength_paragraph().replace("(200)", "(100)")))
    assert not same(doc_value(stated["max_steps"]), {p.name: p.default for p in ARCLENGTH.params}["max_steps"])


def python_blocks(path):
    return re.findall(r"```python\n(.*?)```", read(path), flags=re.S)


FRAGMENTS = [(p, i) for p in ("README.md", "docs/CONTACT.md", "docs/CONTROL.md", "docs/PATHFOLLOWING.md",
                              "docs/SCENARIOS.md") for i in range(len(python_blocks(p)))]


@pytest.mark.parametrize("path,i", FRAGMENTS, ids=[f"{p}[{i}]" for p, i in FRAGMENTS])
def test_documented_python_fragment_runs_and_says_what_its_comments_say(path, i, monkeypatch, capsys):
    """README's contact fragment ran on the magnetic strip of the fragment before it (a ball a
    metre above a 17 mm strip: no contact) and PATHFOLLOWING's passed ``verbose=True``, an
    OptionError since the per-step report became logging; CONTROL's "(6, 3)" is ``J.jacobian``."""
    import logging
    monkeypatch.chdir(ROOT)                       # the fragments read examples/*.toml
    root, core = logging.getLogger(), logging.getLogger("core_se3")
    saved = root.handlers[:], root.level, core.level
    ns = {}
    try:
        exec(compile(python_blocks(path)[i], f"{path}[{i}]", "exec"), ns)
    finally:
        root.handlers[:] = saved[0]
        root.setLevel(saved[1])
        core.setLevel(saved[2])
    if "ball" in python_blocks(path)[i]:
        force = ns["st"].contact["ball"]["force"]
        assert np.allclose(force, [1.337, 0.0, -1.227], atol=1e-3) and ns["st"].balance_error < 1e-9, force
    if "s.jacobian" in python_blocks(path)[i]:
        assert ns["J"].jacobian.shape == (6, 3)
    if "critical_points" in python_blocks(path)[i]:
        assert ns["res"].critical_points[0].describe().startswith("limit point at lam = 0.742123 +- 0.00019")


def test_the_compile_costs_the_auto_backend_counts_are_the_documented_ones():
    from core_se3.backend import NUMBA_COLD_START_COST, NUMBA_START_COST
    text = read("docs/SCENARIOS.md")
    m = re.search(r"numba's start is ([\d.]+) s with the compiled kernels in\s+their cache and about (\d+) s of "
                  r"compilation with an empty cache", text)
    assert m, "docs/SCENARIOS.md: the sentence on numba's start moved"
    assert same(float(m.group(1)), NUMBA_START_COST) and same(float(m.group(2)), NUMBA_COLD_START_COST)
    assert re.search(rf"With a cold cache `auto` counts the {NUMBA_COLD_START_COST:.0f} s", text)


def module_constant(name):
    """The value of a module-level constant ``NAME = ...`` of core_se3 (found in the source, then
    imported), or None when no module defines it."""
    import importlib
    pkg = os.path.join(ROOT, "core_se3")
    for path in sorted(glob.glob(os.path.join(pkg, "**", "*.py"), recursive=True)):
        if re.search(rf"^{name}\s*=", read(path), flags=re.M):
            module = os.path.relpath(path, ROOT)[:-3].replace(os.sep, ".").removesuffix(".__init__")
            return getattr(importlib.import_module(module), name)
    return None


def test_every_constant_a_doc_quotes_with_its_value_has_that_value():
    """`CARRY_MOVE` = 1.5e-4, `GROWTH_SCALE` = 1/2, ...: each named constant the docs quote with a
    value is a module constant of that value."""
    quoted = [(path, n, v) for path in DOCS
              for n, v in re.findall(r"`([A-Z][A-Z0-9_]{2,})` ?= ?([0-9][0-9.e+-]*(?:/[0-9]+)?)", read(path))]
    assert len(quoted) >= 6
    wrong = []
    for path, name, value in quoted:
        num, _, den = value.rstrip(".").partition("/")
        code = module_constant(name)
        if code is None or not same(float(num) / float(den or 1), code):
            wrong.append((path, name, value, code))
    assert not wrong, f"(doc, constant, doc's value, code's value): {wrong}"


def test_every_exception_and_warning_the_docs_name_exists():
    """A renamed exception leaves the docs telling users to catch a name that is not there."""
    import builtins
    import core_se3.errors as errors
    named = {(n, path) for path in DOCS for n in re.findall(r"\b([A-Z][A-Za-z]+(?:Error|Warning))\b", read(path))}
    assert len({n for n, _ in named}) >= 15
    missing = sorted((n, p) for n, p in named if not hasattr(errors, n) and not hasattr(builtins, n))
    assert not missing, missing


def test_the_readme_layout_names_every_doc():
    """README's layout lists what docs/ holds: STEPS and PARALLEL were missing from it."""
    layout = read("README.md").split("## Layout", 1)[1].split("`docs/` —", 1)[1].split("\n* ", 1)[0].lower()
    words = {"pathfollowing": "path following", "steps": "steps", "parallel": "parallel"}
    missing = [d for d in DOCS[1:] if words.get(os.path.basename(d)[:-3].lower(), os.path.basename(d)[:-3].lower())
               not in layout]
    assert not missing, missing


def test_scenarios_prose_states_the_mesh_and_support_defaults():
    """`refine = k` (0 ... MAX_REFINE, default 0) and the supports' default penalty 1e6, stated in
    docs/SCENARIOS.md's prose, outside the generated tables."""
    from core_se3.model.support_kinds import PENALTY_DEFAULT
    from core_se3.scenario.geometry import MAX_REFINE
    text = read("docs/SCENARIOS.md")
    m = re.search(r"`refine = k` \(a whole number, 0 \.\.\. (\d+); default 0\)", text)
    assert m and int(m.group(1)) == MAX_REFINE
    assert same(float(re.search(r"so the\s+default ([\d.e+]+) fits every unit system", text).group(1)), PENALTY_DEFAULT)


# dotted names in the docs that are not core_se3's: other packages, result-document keys, scenario
# keys, local variables of the fragments, files
NOT_CODE = {"scipy", "p", "part", "step", "reference", "parameters", "prob", "reactions", "scn", "regions",
            "roof_modes", "result", "st", "res", "s", "doc", "ex_elast_rmshell_scordelis_lo_roof",
            "ex_elast_rmshell_pinched_cylinder", "sze36_48x48_d"}


def test_every_dotted_name_starts_with_a_module_of_core_se3():
    """`bench_magnetic.MU0_MM`, `solver.newton_solve`, `mesh_shapes.hemisphere_quarter`: names
    under modules that do not exist (catalogue.family_magnetic, solvers, mesh.generators)."""
    import pkgutil
    import core_se3
    modules = {m.name.rsplit(".", 1)[1] for m in pkgutil.walk_packages(core_se3.__path__, "core_se3.")} | {"core_se3"}
    unknown = set()
    for path in DOCS:
        text = re.sub(r"```.*?```", "", read(path), flags=re.S)
        for span in re.findall(r"`([^`\n]+)`", text):
            m = re.match(r"^([a-z_][a-z0-9_]*)\.[A-Za-z_]\w*", span.strip())
            if m and not re.search(r"\.(py|md|toml|json|png|msh|vtu|npz|pvd|csv|txt|sh|dat|m)\b", span):
                first = m.group(1)
                if first not in modules and first not in NOT_CODE and not hasattr(core_se3, first):
                    unknown.add((path, span[:60]))
    assert not unknown, sorted(unknown)
