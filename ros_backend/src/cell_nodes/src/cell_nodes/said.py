"""A text for the user that the app can say in the user's language: the English sentence, a stable code and its
parameters (cell_msgs LogEntry, ProcessState: `code`, `params` as diagnostic_msgs/KeyValue).

`Said` is a `str` (the English): logs, results and tests use it as text, and whatever joins or cuts it gets a plain
string (the app then shows that English). A parameter that is itself `Said` nests: besides `key` (its English) the
parameters carry `key.code` and `key.<its parameter>`, so the app says the inner text in the same language.
The app's catalogue key of a code: its feature, `_said_`, then the rest with `_` for `.`
("process.stop" -> process_said_stop).
"""
from __future__ import annotations

from typing import Sequence


class Said(str):
    code: str
    params: tuple[tuple[str, str], ...]

    def __new__(cls, text: str, code: str = "", params: Sequence[tuple[str, str]] = ()) -> "Said":
        s = super().__new__(cls, text)
        s.code = code
        s.params = tuple(params)
        return s


def say(code: str, template: str, **params: object) -> Said:
    """The English `template` with its {name} parameters filled in (a number as given: round it first)."""
    flat: list[tuple[str, str]] = []
    for k, v in params.items():
        flat.append((k, str(v)))
        if isinstance(v, Said) and v.code:
            flat.append((f"{k}.code", v.code))
            flat.extend((f"{k}.{pk}", pv) for pk, pv in v.params)
    return Said(template.format(**{k: str(v) for k, v in params.items()}), code, flat)


def coded(text: str) -> tuple[str, list[tuple[str, str]]]:
    """The code and parameters of a text ("" and none for a plain string)."""
    return getattr(text, "code", ""), list(getattr(text, "params", ()))
