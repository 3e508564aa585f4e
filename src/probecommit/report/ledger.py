"""The published-numbers ledger: every number a publication prints, with the key it came from.

Why: a reviewer must be able to check that each number in REPRODUCTION.md, a table or a
report follows from the stored results, and nothing typed by hand can pass as computed.
Publishing code never formats a result number itself; it asks a :class:`Ledger` for the
text, which records ``(file, key, fmt, text)``. ``verify`` later resolves every key
against the results again, re-formats the value and compares the string.

Keys name a value in a publication's results tree:

``"<study>:<dotted.path>"``
    ``results/paper/<study>/results.json``; list elements by index
    (``"insertion:results.table_testc.failure_random_k8.old.0"``).
``"claims:<id>.<field>"``
    ``results/paper/claims.json`` (the claims registry's computed entries).
``"paper:<item>"``
    the paper-values table (``probecommit.studies.paper_values``).
``"reproduction:<dotted.path>"``
    ``results/paper/reproduction.json`` (wall times, engine calls, the machine).

The ledger file is ``published_numbers.json`` at the publication root::

    {"version": 1, "numbers": [{"file": "REPRODUCTION.md", "key": "...",
                                "fmt": ".3f", "text": "0.102"}, ...]}

Entries of one file are recorded in the order they are printed; ``check`` finds each one
after the previous, so an edit that moves a number's text is caught too.
``file`` is relative to the publication root (``REPRODUCTION.md`` sits one level above
``results/paper`` in the checkout and is written ``"../../REPRODUCTION.md"``).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from probecommit.store.safefile import write_text

LEDGER_NAME = "published_numbers.json"
LEDGER_VERSION = 1
#: ``fmt`` of a declared literal: a number printed as text that comes from no result (a table's
#: number "Table V", a section "Sec. V-D", a budget in a heading), with its reason as the key.
LITERAL = "literal"
#: A number as ``uncovered`` reads it in a ledgered file.
NUMBER = re.compile(r"(?<![\w.])[+-]?(?:\d+\.\d+|\d+)(?![\w])")


def format_value(value: Any, fmt: str) -> str:
    """One formatting rule for publishing and for verify: ``format(value, fmt)``.

    ``fmt`` is a format spec (``".3f"``, ``"+.3f"``, ``"d"``, ``".1%"``); ``"d"`` accepts a
    float that is integral. NaN and inf print as ``nan``/``inf`` so verify can refuse them.
    """
    if fmt == "d":
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        return format(int(value), "d")
    return format(float(value), fmt)


@dataclass(frozen=True)
class Entry:
    file: str
    key: str
    fmt: str
    text: str


@dataclass
class Ledger:
    """Collects the numbers one publication prints. One ledger per publication root."""

    entries: list[Entry] = field(default_factory=list)

    def num(self, file: str, key: str, value: Any, fmt: str = ".3f") -> str:
        """The text for ``value`` under ``fmt``, recorded against ``key`` in ``file``."""
        text = format_value(value, fmt)
        self.entries.append(Entry(file=file, key=key, fmt=fmt, text=text))
        return text

    def literal(self, file: str, text: str, why: str) -> str:
        """Declare ``text`` (which holds a number) as printed literally in ``file``, for ``why``."""
        self.entries.append(Entry(file=file, key=f"{LITERAL}:{why}", fmt=LITERAL, text=text))
        return text

    def for_file(self, file: str) -> Callable[..., str]:
        """A ``num`` bound to one file: ``n = ledger.for_file("REPRODUCTION.md"); n(key, v)``."""

        def bound(key: str, value: Any, fmt: str = ".3f") -> str:
            return self.num(file, key, value, fmt)

        return bound

    def to_json(self) -> dict[str, Any]:
        return {"version": LEDGER_VERSION, "numbers": [e.__dict__ for e in self.entries]}

    def write(self, root: str | Path) -> Path:
        path = Path(root) / LEDGER_NAME
        write_text(path, json.dumps(self.to_json(), indent=1) + "\n")
        return path


def read(root: str | Path) -> list[Entry]:
    """The ledger of a publication root; a clear error if it is missing or malformed."""
    path = Path(root) / LEDGER_NAME
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no published-numbers ledger (publish writes it)")
    payload = json.loads(path.read_text())
    if not isinstance(payload, dict) or payload.get("version") != LEDGER_VERSION:
        raise ValueError(f"{path}: not a version-{LEDGER_VERSION} ledger")
    return [Entry(**e) for e in payload["numbers"]]


def _step(node: Any, part: str) -> Any:
    if isinstance(node, list):
        return node[int(part)]
    if isinstance(node, dict):
        return node[part]
    raise KeyError(part)


def resolve(key: str, root: str | Path, extra: dict[str, Any] | None = None) -> Any:
    """The value ``key`` names under publication ``root`` (see the module docstring).

    ``extra`` maps a prefix (``"paper"``) to an in-memory tree, for sources that are not files.
    Dotted parts are tried greedily: a dict key may itself contain dots (``"B.cost_table"``).
    """
    prefix, _, path = key.partition(":")
    node = extra[prefix] if extra and prefix in extra else load_tree(prefix, root)
    return _walk_dotted(node, path.split(".") if path else [])


def load_tree(prefix: str, root: str | Path) -> Any:
    """The JSON file a key prefix names: ``claims.json``, ``reproduction.json`` or ``<study>/results.json``."""
    name = {"claims": "claims.json", "reproduction": "reproduction.json"}.get(prefix, f"{prefix}/results.json")
    return json.loads((Path(root) / name).read_text())


def _walk_dotted(node: Any, parts: list[str]) -> Any:
    if not parts:
        return node
    # Longest dict key first, so "B.cost_table" beats "B" when both could match.
    for n in range(len(parts), 0, -1):
        head = ".".join(parts[:n])
        try:
            child = _step(node, head)
        except (KeyError, IndexError, ValueError, TypeError):
            continue
        try:
            return _walk_dotted(child, parts[n:])
        except KeyError:
            continue
    raise KeyError(".".join(parts))


def check(entries: list[Entry], root: str | Path, extra: dict[str, Any] | None = None) -> Iterator[str]:
    """Problems with a ledger: each entry's key re-resolved and re-formatted, and its text found."""
    texts: dict[str, str] = {}
    cursor: dict[str, int] = {}
    trees: dict[str, Any] = dict(extra or {})  # each JSON file read once, not once per entry
    for e in entries:
        if e.fmt == LITERAL:
            yield from _find(e, root, texts, cursor)
            continue
        try:
            prefix = e.key.partition(":")[0]
            if prefix not in trees:
                trees[prefix] = load_tree(prefix, root)
            value = resolve(e.key, root, trees)
            again = format_value(value, e.fmt)
        except (KeyError, IndexError, ValueError, TypeError, FileNotFoundError) as exc:
            yield f"{e.file}: {e.text} names {e.key}, which does not resolve ({exc})"
            continue
        if isinstance(value, float) and not math.isfinite(value):
            yield f"{e.file}: {e.key} is {value} (a published number must be finite)"
        if again != e.text:
            yield f"{e.file}: prints {e.text} for {e.key}, which formats as {again}"
        if e.file not in texts:
            path = Path(root) / e.file
            texts[e.file] = path.read_text() if path.is_file() else ""
            if not path.is_file():
                yield f"{e.file}: listed in the ledger but missing"
        # Entries of one file are recorded in reading order: each must appear after the last.
        at = texts[e.file].find(e.text, cursor.get(e.file, 0))
        if at < 0:
            yield f"{e.file}: does not contain {e.text} ({e.key}) where the ledger places it"
        else:
            cursor[e.file] = at + len(e.text)


def walk_dotted(node: Any, parts: list[str]) -> Any:
    """The value at dotted ``parts`` under ``node`` (dict keys may hold dots; list elements by index).

    Public for ``verify``, which compares recomputed values with the results tree by the same keys.
    """
    return _walk_dotted(node, parts)


def _find(e: Entry, root: str | Path, texts: dict[str, str], cursor: dict[str, int]) -> Iterator[str]:
    """Find a literal entry's text after the previous entry of its file."""
    if e.file not in texts:
        path = Path(root) / e.file
        texts[e.file] = path.read_text() if path.is_file() else ""
    at = texts[e.file].find(e.text, cursor.get(e.file, 0))
    if at < 0:
        yield f"{e.file}: does not contain the declared literal {e.text!r} ({e.key}) where the ledger places it"
    else:
        cursor[e.file] = at + len(e.text)


def uncovered(entries: list[Entry], root: str | Path) -> Iterator[str]:
    """Numbers printed in a ledgered file that no entry (or declared literal) accounts for.

    Entries are matched in reading order, as ``check`` does; every number outside the spans they
    match is one problem, named by file, line and text, so a number typed into prose fails.
    """
    by_file: dict[str, list[Entry]] = {}
    for e in entries:
        by_file.setdefault(e.file, []).append(e)
    for file, mine in by_file.items():
        path = Path(root) / file
        if not path.is_file():
            continue
        text = path.read_text()
        spans, at = [], 0
        for e in mine:
            found = text.find(e.text, at)
            if found >= 0:
                spans.append((found, found + len(e.text)))
                at = found + len(e.text)
        covered = iter(sorted(spans))
        span = next(covered, None)
        for m in NUMBER.finditer(text):
            while span is not None and span[1] <= m.start():
                span = next(covered, None)
            if span is None or not (span[0] <= m.start() and m.end() <= span[1]):
                line = text.count("\n", 0, m.start()) + 1
                yield f"{file}: prints {m.group(0)} at line {line}, which no ledger entry or declared literal accounts for"
