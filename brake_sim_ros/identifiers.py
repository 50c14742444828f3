"""The one rule for an identifier the product writes into file names, metadata and
messages: a run id, a brake unit's id, a campaign's name.

1 to 64 characters of ``A-Z a-z 0-9 _ . -``, not starting with '.' or '-': safe as a file
or directory name on every common file system (no separator, no hidden file) and never
read as a command-line option.

Pure logic: no files.
"""

from __future__ import annotations

import re

_IDENTIFIER = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}")
# what an identifier may be, for messages and parameter descriptions
IDENTIFIER_RULE = "1 to 64 characters of A-Z a-z 0-9 _ . -, not starting with '.' or '-'"


def is_identifier(value: object) -> bool:
    """``value`` is a string that follows the rule (module doc)."""
    return isinstance(value, str) and _IDENTIFIER.fullmatch(value) is not None
