"""Test helper: a text a node says with a code (cell_nodes/said.py) against the app's catalogues
(app/messages/<feature>/<lang>.json)."""
from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any, Optional

from cell_nodes.said import Said, coded

APP_MESSAGES = Path(__file__).resolve().parents[4] / "app" / "messages"
LANGS = ("en", "es", "fi", "de")
_catalogues: dict[tuple[str, str], dict[str, Any]] = {}


def _catalogue(feature: str, lang: str) -> dict[str, Any]:
    if (feature, lang) not in _catalogues:
        _catalogues[feature, lang] = json.loads((APP_MESSAGES / feature / f"{lang}.json").read_text())
    return _catalogues[feature, lang]


def _templates(entry: Any, count: Optional[str]) -> tuple[list[str], str]:
    """A catalogue entry's texts (every plural form) and the one English uses for this count."""
    if isinstance(entry, str):
        return [entry], entry
    forms = entry[0]["match"]
    return list(forms.values()), forms["countPlural=one" if count == "1" else "countPlural=other"]


def check_said(text: str) -> None:
    """A text a node says with a code: its key is in every language's catalogue (app/src/lib/core/said.js), with the
    same parameters; the English catalogue text is the node's English; nested parameters alike."""
    code, params = coded(text)
    if not code:
        return
    flat = dict(params)
    top = {k: v for k, v in params if "." not in k}
    if code.startswith("alarm."):   # an alarm's code: the alarms feature's catalogue (test_alarms_logic.py)
        for lang in LANGS:
            assert "alarms_code_" + code[6:].replace(".", "_") in _catalogue("alarms", lang), (lang, code)
        return
    feature, rest = code.split(".", 1)
    key = f"{feature}_said_{rest.replace('.', '_')}"
    for lang in LANGS:
        cat = _catalogue(feature, lang)
        assert key in cat, f"{lang}: no {key} for {text!r}"
        forms, _ = _templates(cat[key], top.get("count"))
        for form in forms:
            assert set(re.findall(r"\{(\w+)\}", form)) == set(top), (lang, key, form, top)
    assert _templates(_catalogue(feature, "en")[key], top.get("count"))[1].format(**top) == str(text), (key, text)
    for k, v in top.items():
        if f"{k}.code" in flat:
            check_said(Said(v, flat[f"{k}.code"], [(kk[len(k) + 1:], vv) for kk, vv in params
                                                    if kk.startswith(f"{k}.") and kk != f"{k}.code"]))
