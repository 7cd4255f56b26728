"""Every text a node says with a code (`say(code, template, ...)` anywhere in cell_nodes, its scripts included) is in
the app's catalogue in every language, with the same parameters, and the English catalogue text is the node's
template: a node cannot say something the app cannot translate (the runs of test_process_logic.py check the
texts as said, nesting included)."""
from __future__ import annotations

import ast
import re
from pathlib import Path
from typing import Iterator

import pytest

from said_check import LANGS, _catalogue, _templates

PKG = Path(__file__).resolve().parents[1]
SOURCES = sorted([*PKG.glob("src/cell_nodes/**/*.py"), *(p for p in (PKG / "scripts").iterdir() if p.is_file())])


def said_calls() -> Iterator[tuple[str, str, str, frozenset[str]]]:
    """(where, code, template, parameter names) of every say() with a literal code and template."""
    for path in SOURCES:
        tree = ast.parse(path.read_text(), str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "say" and len(node.args) >= 2:
                code, template = node.args[0], node.args[1]
                if isinstance(code, ast.Constant) and isinstance(template, ast.Constant):
                    yield (f"{path.relative_to(PKG)}:{node.lineno}", code.value, template.value,
                           frozenset(k.arg for k in node.keywords if k.arg))


CALLS = list(said_calls())


def test_the_scan_finds_the_nodes_texts() -> None:
    codes = {c for _, c, _, _ in CALLS}
    assert {"manual.unreachable", "manual.jog_refused", "process.done"} <= codes, sorted(codes)[:20]


@pytest.mark.parametrize("where,code,template,params", CALLS, ids=[f"{c}@{w}" for w, c, _, _ in CALLS])
def test_said_text_is_in_every_catalogue(where: str, code: str, template: str, params: frozenset[str]) -> None:
    assert set(re.findall(r"\{(\w+)\}", template)) == params, f"{where}: the template's parameters are not its keywords"
    feature, rest = code.split(".", 1)
    key = f"{feature}_said_{rest.replace('.', '_')}"
    for lang in LANGS:
        cat = _catalogue(feature, lang)
        assert key in cat, f"{where}: {lang} has no {key} ({template!r})"
        forms, _ = _templates(cat[key], None)
        for form in forms:
            assert set(re.findall(r"\{(\w+)\}", form)) == params, (where, lang, key, form)
    english, _ = _templates(_catalogue(feature, "en")[key], None)
    assert template in english, f"{where}: the English catalogue says {english} for {key}, the node {template!r}"


def test_one_code_one_text() -> None:
    seen: dict[str, tuple[str, str]] = {}
    for where, code, template, _ in CALLS:
        first = seen.setdefault(code, (where, template))
        assert first[1] == template, f"{code}: {first[0]} says {first[1]!r}, {where} {template!r}"
