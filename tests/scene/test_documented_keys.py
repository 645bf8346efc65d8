"""docs/scene-format.md documents every key the scene reader accepts: each key of each
table's rules appears, in backquotes, in that table's section of the page (the sub-tables
of a step in the step's section)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from dolfinx_friction.scene.model import RULES

PAGE = Path(__file__).resolve().parents[2] / "docs" / "scene-format.md"
#: the heading of the section that documents each table of the rules ("": the top level)
SECTIONS = {"": "The top level", "body": "`[[body]]`", "rigid": "`[[rigid]]`",
            "contact": "`[[contact]]`", "step": "`[[step]]`", "step.bc": "`[[step]]`",
            "step.load": "`[[step]]`", "step.rigid": "`[[step]]`", "output": "`[output]`",
            "solver": "`[solver]`"}


def _section(heading: str) -> str:
    text = PAGE.read_text()
    match = re.search(rf"^## {re.escape(heading)}.*?$(.*?)(?=^## |\Z)", text, re.M | re.S)
    assert match, f"docs/scene-format.md: no section '## {heading}'"
    return match.group(1)


@pytest.mark.parametrize("rules", list(RULES.values()), ids=lambda r: r.table or "top")
def test_every_key_is_documented(rules):
    section = _section(SECTIONS[rules.table])
    missing = [key for key in rules.keys if f"`{key}`" not in section]
    assert not missing, f"docs/scene-format.md, {SECTIONS[rules.table]}: {missing} undocumented"
