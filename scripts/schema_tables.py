#!/usr/bin/env python3
"""Rewrite the generated tables of docs/SCENARIOS.md (the blocks between ``<!-- schema: NAME -->``
and ``<!-- /schema -->``) from the vocabulary (``core_se3.scenario.schema.update_doc``):

    python scripts/schema_tables.py [FILE ...]        # default docs/SCENARIOS.md
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from core_se3.scenario.schema import update_doc  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

for path in sys.argv[1:] or [os.path.join(ROOT, "docs", "SCENARIOS.md")]:
    with open(path, encoding="utf-8") as fh:
        old = fh.read()
    new = update_doc(old)
    if new != old:
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(new)
    print(f"{path}: {'updated' if new != old else 'up to date'}")
