"""The cell file's texts as a node reads them (no YAML here: the power-loss test's child imports it without site
packages)."""
from __future__ import annotations

from typing import Any


def english(value: Any) -> Any:
    """A text the page shows may be one per language ({en: ..., es: ...}, the schema's $defs/text): a node keeps the
    English. Anything else comes back as it is, for the caller to check."""
    return value.get("en") if isinstance(value, dict) else value
