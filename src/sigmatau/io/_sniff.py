"""Sniffing a text log from its first lines: delimiter, header, units line, numeric columns.

The parser (:mod:`._text`) reads the rest in chunks with what this finds.
"""

from __future__ import annotations

import csv
import functools
import io
import re
from collections import Counter
from typing import Iterator

from ..errors import DataError
from ._columns import recognise, time_name
from ._errors import FormatError, option_hint
from ._limits import MAX_LINE_CHARS
from ._units import canonical_unit, time_unit_name

__all__: list[str] = []

_DELIMITERS: tuple[str | None, ...] = ("\t", ",", ";", "|", None)
_DELIMITER_NAMES = {"\t": "tab", ",": "comma", ";": "semicolon", "|": "pipe", None: "whitespace"}


_COMMENTS = ("#", "%", "//")


_SNIFF_ROWS = 200


_SNIFF_MAX_LINES = 20_000


_INT = re.compile(r"^[+-]?\d+$")


_DECIMAL_COMMA = re.compile(r"^[+-]?\d+,\d+(?:[eE][+-]?\d+)?$")


def _strip_comment(line: str) -> str:
    cut = len(line)
    for c in _COMMENTS:
        k = line.find(c)
        if k != -1:
            cut = min(cut, k)
    return line[:cut]


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return line.split()
    if not line:
        return []
    if '"' not in line:  # what the csv module would return, without its 131,072-character field limit
        return [f.strip() for f in line.split(delimiter)]
    try:
        fields = next(csv.reader([line], delimiter=delimiter, quotechar='"', skipinitialspace=True), [])
    except csv.Error:  # a quoted field over the csv module's limit: not a number nor a name anyway
        return [f.strip().strip('"') for f in line.split(delimiter)]
    return [f.strip() for f in fields]


def _shown(value: str) -> str:
    """A field for a one-line message: quoted, at most 40 characters of it."""
    if not value:
        return "an empty field"
    return repr(value) if len(value) <= 40 else repr(value[:40]) + f"… ({len(value):,} characters)"


def _lines(text: io.TextIOWrapper) -> Iterator[str]:
    """Lines of at most MAX_LINE_CHARS characters: a longer line arrives cut and is refused
    by :func:`_check_lengths` instead of being held whole in memory."""
    return iter(functools.partial(text.readline, MAX_LINE_CHARS), "")


def _check_lengths(lines: list[str], first: int, display: str) -> None:
    if lines and max(map(len, lines)) >= MAX_LINE_CHARS:
        k = next(i for i, s in enumerate(lines) if len(s) >= MAX_LINE_CHARS)
        raise DataError(
            f"{display}: line {first + k} is longer than {MAX_LINE_CHARS:,} characters; not a table of numbers"
        )


def _is_num(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return "_" not in s


def _tail(split: list[list[str]]) -> tuple[list[list[str]], int, bool]:
    """The last lines (at most 20, at most half), their usual field count, and whether 80 % have it."""
    tail = split[-min(20, (len(split) + 1) // 2):]
    counts = Counter(len(f) for f in tail)
    c, hits = max(counts.items(), key=lambda kv: (kv[1], kv[0]))
    return tail, c, hits >= 0.8 * len(tail)


def _single_name(line: str) -> bool:
    """Whether a line can name a lone column: one word, or a channel or time name with a unit."""
    text = line.strip().strip('"')
    return len(text.split()) == 1 or recognise(text).group is not None or time_name(text) is not None


def _is_units_line(fields: list[str]) -> bool:
    """Whether a line under the header gives units: no numbers, every field a known unit or
    bracketed, at least one known or all bracketed (unknown ones are then refused by name,
    not skipped as a preamble line and replaced by a default unit)."""
    present = [x for x in fields if x]
    if not present or any(_is_num(x) for x in present):
        return False
    known = [bool(canonical_unit(x.strip("[]()")) or time_unit_name(x.strip("[]()"))) for x in present]
    bracketed = [x[:1] in "[(" and x[-1:] in "])" for x in present]
    short = all(len(x) <= 24 and len(x.split()) <= 3 for x in present)
    return short and (all(known) or all(bracketed) or (any(known) and all(k or len(x.split()) == 1
                                                                          for k, x in zip(known, present))))


def _mostly_numeric(values: list[str]) -> bool:
    good = sum(_is_num(v) for v in values)
    return good > 0 and 2 * good > len(values)


class _Sniff:
    """Layout of a text file from its first lines."""

    def __init__(self, head: list[str], delimiter: str | None, display: str, given_delimiter: bool):
        self.display = display
        entries = [(i + 1, line.rstrip("\r\n")) for i, line in enumerate(head)]
        self.comments = [(n, s) for n, s in entries if s.strip().startswith(_COMMENTS)]
        rows = [(n, s) for n, s in entries if s.strip() and not s.strip().startswith(_COMMENTS)]
        if not rows:
            raise DataError(f"{display}: no numeric data (only comments or blank lines)")
        self.delimiter = delimiter if given_delimiter else self._choose(rows)
        d = self.delimiter
        split = [_split(_strip_comment(s), d) for _, s in rows]
        tail, c, consistent = _tail(split)
        if not consistent:
            raise FormatError(
                f"{display}: not a table of numbers: its last lines split into different numbers of"
                f" fields ({_DELIMITER_NAMES.get(d, repr(d))} delimiter); if it is a table, give its delimiter"
                f" with {option_hint('--delimiter', 'delimiter=')}"
            )
        self.ncols = c
        tail = [f for f in tail if len(f) == c]
        # a column is numeric when most of the last lines hold numbers there: a stray bad value
        # is then reported with its line number by the parser instead of hiding the column
        self.numeric = [_mostly_numeric([f[j] for f in tail]) for j in range(c)]
        self.first_bad = [next((f[j] for f in tail if not _is_num(f[j])), None) for j in range(c)]
        if not any(self.numeric):
            raise DataError(f"{display}: no numeric data (no column of the last lines holds numbers)")
        start = next(
            k for k, f in enumerate(split)
            if len(f) == c and all(_is_num(f[j]) for j in range(c) if self.numeric[j])
        )
        self.data_line = rows[start][0]
        self.preamble = rows[:start]
        self.tail = tail
        self.header_line: int | None = None
        names: list[str] | None = None
        for n, s in self.preamble:
            f = [s.strip()] if c == 1 else _split(s, d)
            if len(f) == c and (c > 1 or _single_name(s)):
                names, self.header_line = f, n
                break
        if names is None:
            before = [(n, s) for n, s in self.comments if n < self.data_line]
            if before and not any(n > before[-1][0] for n, _ in self.preamble):
                n, s = before[-1]
                body = s.strip()
                for mark in _COMMENTS:
                    if body.startswith(mark):
                        body = body[len(mark):].strip()
                        break
                f = ([body] if c == 1 else _split(body, d)) if body else []
                if len(f) == c and (c > 1 or _single_name(body)) and not all(_is_num(x) for x in f):
                    names, self.header_line = f, n
        self.has_header = names is not None
        self.names = self._names(names, c)
        for n, s in self.preamble:
            f = _split(_strip_comment(s), d)
            if n != self.header_line and len(f) == c and c > 1:
                nums = [j for j in range(c) if self.numeric[j] and _is_num(f[j])]
                bad = [j for j in range(c) if self.numeric[j] and not _is_num(f[j])]
                if nums and bad:  # a data line with a damaged value, not a preamble line
                    j = bad[0]
                    raise DataError(
                        f"{display}: line {n}: {_shown(f[j])} in column {self.names[j]!r} is not a number")
        self.units_line: dict[str, str] = {}
        after = [(n, s) for n, s in self.preamble if self.header_line and n > self.header_line]
        for _, s in after:
            f = _split(s, d)
            if len(f) == c and _is_units_line(f):
                self.units_line = {self.names[j]: f[j].strip("[]()") for j in range(c) if f[j]}
        self.skipped = sum(1 for n, _ in self.preamble if n != self.header_line)
        self.text = " ".join(s for _, s in self.comments + self.preamble)

    @staticmethod
    def _names(names: list[str] | None, c: int) -> list[str]:
        if names is None:
            return [f"col{j}" for j in range(c)]
        out: list[str] = []
        for j, raw in enumerate(names):
            name = raw.strip().strip('"').strip("'").strip() or f"col{j}"
            if name in out:
                name = f"{name}_{j}"
            out.append(name)
        return out

    def _choose(self, rows: list[tuple[int, str]]) -> str | None:
        best: tuple | None = None
        choice: str | None = None
        for pref, d in enumerate(_DELIMITERS):
            split = [_split(_strip_comment(s), d) for _, s in rows]
            tail, c, consistent = _tail(split)
            tail = [f for f in tail if len(f) == c]
            nnum = sum(_mostly_numeric([f[j] for f in tail]) for j in range(c)) if consistent else 0
            key = (consistent and nnum > 0, nnum, c, -pref)
            if best is None or key > best:
                best, choice = key, d
        assert best is not None
        if best[2] == 1:
            choice = None
        comma_split = _tail([_split(_strip_comment(s), ",") for _, s in rows])[0]
        if choice == "," and not all(_is_num(x) for f in comma_split for x in f):
            for alt in (";", "\t", None):
                tail = _tail([_split(_strip_comment(s), alt) for _, s in rows])[0]
                if all(len(f) == len(tail[-1]) for f in tail) and all(
                    all(_is_num(x) or _DECIMAL_COMMA.match(x) for x in f) for f in tail
                ) and any(_DECIMAL_COMMA.match(x) for f in tail for x in f):
                    raise FormatError(
                        f"{self.display}: the numbers use decimal commas (such as {tail[-1][0]!r}),"
                        " which are not supported; convert them to decimal points"
                    )
        return choice


def _read_head(text: io.TextIOWrapper, display: str) -> list[str]:
    head: list[str] = []
    rows = 0
    for line in _lines(text):
        _check_lengths([line], len(head) + 1, display)
        head.append(line)
        s = line.strip()
        if s and not s.startswith(_COMMENTS):
            rows += 1
        if rows >= _SNIFF_ROWS or len(head) >= _SNIFF_MAX_LINES:
            break
    sample = "".join(head[:200])
    if "\x00" in sample or sample.count("\ufffd") > max(2, len(sample) // 100):
        raise FormatError(f"{display}: not a text file (binary content) and not a recognised binary format")
    if not head:
        raise DataError(f"{display}: the file is empty")
    return head
