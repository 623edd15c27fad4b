"""Packaged reference data (core_se3/data): loading and parsing."""
import pytest

from core_se3.catalogue import references as refs


def test_elastica_kirchhoff_cantilever_entry_parsed():
    # elastica.json["1_cantilever_tip_force_kirchhoff"]
    e = refs.elastica_entry("1_cantilever_tip_force_kirchhoff")
    assert isinstance(e["params"], dict)
    assert e["params"]["EI"] == 1.0
    assert isinstance(e["load"], list) and isinstance(e["tip"]["v"], list)
    assert len(e["load"]) == len(e["tip"]["v"]) == 41
    assert e["load"][0] == 0.0 and e["load"][-1] == 10.0


def test_elastica_entry_bad_name_lists_available():
    with pytest.raises(KeyError) as exc:
        refs.elastica_entry("no_such_case")
    msg = str(exc.value)
    assert "no_such_case" in msg
    assert "1_cantilever_tip_force_kirchhoff" in msg
    with pytest.raises(KeyError):
        refs.elastica_entry("_meta")


def test_literal_strings_are_parsed():
    parse = refs._parse_literals
    out = parse({"params": "{'EI': 1.0, 'L': 2}", "load": "[0.0, 0.5]", "x": "1e-3",
                 "text": "Sze (2004)", "key": "1_cantilever"})
    assert out == {"params": {"EI": 1.0, "L": 2}, "load": [0.0, 0.5], "x": 1e-3,
                   "text": "Sze (2004)", "key": "1_cantilever"}


def test_loaders_cached_and_copies():
    a = refs.load_elastica()
    a["1_cantilever_tip_force_kirchhoff"]["params"]["EI"] = -1
    assert refs.elastica_entry("1_cantilever_tip_force_kirchhoff")["params"]["EI"] == 1.0
    lit = refs.load_literature()
    assert "benchmarks" in lit
    # literature.json benchmark "sze3.1_cantilever_end_shear"
    b = refs.literature_entry("sze3.1_cantilever_end_shear")
    assert len(b["P_over_Pmax"]) == len(b["W_tip"])
    with pytest.raises(KeyError, match="sze3.1_cantilever_end_shear"):
        refs.literature_entry("nope")
