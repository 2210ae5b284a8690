"""Fast path for plain delimited text: pyarrow's multi-threaded CSV parser (issue 13).

:mod:`._text` sniffs the file and chooses its columns as always; when the file is a plain
case this module then parses the data lines with ``pyarrow.csv.read_csv`` straight into
float64 (int64 for large integer time tags) columns, hashing the bytes in the same pass.
It gives the same table as the reference parser (``numpy.loadtxt`` in chunks) or gives up
by raising :class:`Fallback`, and the reference parser then reads the file from the start of
its data: it never produces another answer and never writes its own error messages.

Why it is exact
---------------
The data region, from the first data line to the end of the file, is cut into ranges that end
after a ``\\n`` byte, and each range is parsed with quoting, escaping, null spellings and empty
line skipping all switched off, with exactly ``ncols`` fields demanded on every line.
pyarrow's number grammar is a subset of the one ``numpy.loadtxt`` accepts, its float parsing
rounds correctly (fast_float) like numpy's, and integers are exact in both. Then:

* a line that pyarrow accepts splits into the same fields for ``numpy.loadtxt`` (no quotes, no
  comment marker — any ``#`` in the data region gives up) and the chosen fields give the same
  numbers, so the reference would accept it too, with the same values;
* a line the reference would refuse (a bad value, too few fields, an empty line, a comment) is
  refused by pyarrow as well, which must also see the full field count on every line: the
  reference then reports it with its own message and line number;
* pyarrow's int64 conversion alone accepts hexadecimal (``0x1F``): with an integer time column,
  ``0x`` or ``0X`` anywhere in the data region gives up;
* non-finite values (``nan``, ``inf``, overflow) give up, so the bits of NaNs and the
  spellings of infinity never depend on which parser read them;
* a line longer than ``MAX_LINE_CHARS`` (refused by the reference) cannot pass: every aligned
  window of ``MAX_LINE_CHARS // 4`` bytes of a range must hold a newline;
* a UTF-8 byte-order mark at the start of a range gives up: pyarrow would skip it, the
  reference keeps it inside the field (only the file's own first bytes lose theirs);
* the byte offset of the first data line is checked by decoding the bytes before it the way
  the reference did and comparing with the lines it sniffed.
"""

from __future__ import annotations

import hashlib
import queue
import threading
from typing import Iterator, Sequence

import numpy as np

from ._limits import MAX_LINE_CHARS

__all__: list[str] = []

#: Bytes handed to one ``read_csv`` call: large enough that its start-up costs nothing, small
#: enough that the pyarrow table of one range (about half the text) adds little to the peak.
RANGE_BYTES = 32 << 20
#: pyarrow's block size inside a range: a few blocks per range keep both cores parsing. It must
#: exceed the longest line the window check lets through (``2 * _WINDOW``), or pyarrow refuses it.
BLOCK_BYTES = 4 << 20
#: Every aligned window this long must hold a newline: a line then has fewer than
#: ``2 * _WINDOW`` bytes, well under the reference's ``MAX_LINE_CHARS`` characters.
_WINDOW = MAX_LINE_CHARS // 4
#: Delimiters for which pyarrow's splitting is exactly ``str.split`` (no quotes): not whitespace runs.
DELIMITERS = (",", ";", "\t", "|")
_BOM = b"\xef\xbb\xbf"

#: What the last read did, for tests and benchmarks: "fast", or why the fast path gave up.
last_outcome = ""


class Fallback(Exception):
    """The fast path cannot prove it would give the reference parser's answer: use the reference."""


def usable() -> bool:
    """Whether pyarrow's CSV reader can be imported (imported here only, when a CSV is read)."""
    try:
        import pyarrow.csv  # noqa: F401
    except ImportError:
        return False
    return True


def _data_offset(raw: bytes, prefix: str) -> int | None:
    """The byte offset where the line after ``prefix`` (the file's first lines, as decoded) starts.

    None when ``raw`` (the file's first bytes) is too short to tell or the bytes before the offset
    do not decode (UTF-8 with a byte-order mark stripped, errors replaced, universal newlines)
    to exactly ``prefix``.
    """
    lines = prefix.count("\n")
    if lines == 0:
        return 0 if not prefix else None
    pos = 0
    for _ in range(lines):
        k = raw.find(b"\n", pos)
        if k < 0:
            return None
        pos = k + 1
    text = raw[:pos].decode("utf-8-sig", errors="replace").replace("\r\n", "\n").replace("\r", "\n")
    return pos if text == prefix else None


def _line_windows_ok(buf: bytes | memoryview, data_from: int) -> bool:
    """Whether every full aligned window of ``_WINDOW`` bytes from ``data_from`` holds a newline."""
    end = len(buf) - _WINDOW
    i = data_from
    while i <= end:
        if buf.find(b"\n", i, i + _WINDOW) < 0:  # type: ignore[union-attr]
            return False
        i += _WINDOW
    return True


class FastReader:
    """The data lines of a plain delimited file parsed by pyarrow, the whole file hashed.

    Parameters
    ----------
    path : str or os.PathLike
        A regular, uncompressed file.
    prefix : str
        The text before the first data line, as the reference decoded it (its sniffed lines).
    delimiter : str
        One of :data:`DELIMITERS`.
    ncols : int
        Fields on every data line.
    usecols : sequence of int
        Columns to read, the time column first when ``int_time``.
    int_time : bool
        Read the first of ``usecols`` as int64 (time tags beyond 2**53), the others as float64.

    Notes
    -----
    :meth:`batches` yields the chosen columns range by range and raises :class:`Fallback` on
    anything it cannot prove equal to the reference; afterwards :attr:`sha256` and
    :attr:`nbytes` describe every byte of the file. A thread reads and hashes the file ahead
    of the parsing (``hashlib`` and pyarrow both release the GIL).
    """

    def __init__(self, path, prefix: str, delimiter: str, ncols: int, usecols: Sequence[int],
                 int_time: bool) -> None:
        if delimiter not in DELIMITERS:
            raise Fallback(f"delimiter {delimiter!r}")
        self.path = path
        self.prefix = prefix
        self.delimiter = delimiter
        self.ncols = ncols
        self.usecols = list(usecols)
        self.int_time = int_time
        self.sha256 = ""
        self.nbytes = 0  # bytes read (and hashed) so far
        self._stop = threading.Event()

    def _options(self):  # type: ignore[no-untyped-def]
        import pyarrow as pa
        import pyarrow.csv as pcsv

        names = [f"c{j}" for j in range(self.ncols)]
        chosen = [names[j] for j in self.usecols]
        types = {name: pa.float64() for name in chosen}
        if self.int_time:
            types[chosen[0]] = pa.int64()
        read = pcsv.ReadOptions(column_names=names, block_size=BLOCK_BYTES, use_threads=True)
        # no quoting and no empty-line skipping: each line splits like str.split(delimiter)
        parse = pcsv.ParseOptions(delimiter=self.delimiter, quote_char=False, double_quote=False,
                                  escape_char=False, newlines_in_values=False, ignore_empty_lines=False)
        # no spelling of a missing value: an empty or "NA" field is an error, as for the reference
        convert = pcsv.ConvertOptions(column_types=types, include_columns=chosen, null_values=[],
                                      true_values=[], false_values=[], strings_can_be_null=False,
                                      quoted_strings_can_be_null=False)
        return read, parse, convert

    def _produce(self, out: queue.Queue) -> None:
        """Reader thread: hash every byte; queue the data region in ranges ending after a newline."""
        sha = hashlib.sha256()
        try:
            with open(self.path, "rb", buffering=0) as fh:
                first = fh.read(max(RANGE_BYTES, 4 * len(self.prefix) + 3 * self.prefix.count("\n") + 16))
                sha.update(first)
                nbytes = len(first)
                offset = _data_offset(first, self.prefix)
                if offset is None:
                    raise Fallback("the first data line's byte offset is not certain")
                carry = first[offset:]
                eof = not first
                while not eof and not self._stop.is_set():
                    piece = fh.read(RANGE_BYTES)
                    eof = not piece
                    if piece:
                        sha.update(piece)
                        nbytes += len(piece)
                        buf = carry + piece
                    else:
                        buf = carry
                    # the last range may end without a newline (so may the file)
                    cut = len(buf) if eof else buf.rfind(b"\n") + 1
                    if cut == 0 and len(buf) < 2 * _WINDOW:
                        carry = buf  # no newline yet in a short read: read on
                        continue
                    # the range is a view of buf (no copy of tens of MB); only the short tail is copied
                    chunk, carry = memoryview(buf)[:cut], buf[cut:]
                    if not _line_windows_ok(buf, 0):
                        raise Fallback("a line may exceed the line-length limit")
                    if buf.find(b"#", 0, cut) >= 0:
                        raise Fallback("a '#' in the data (a comment)")
                    # pyarrow's int64 conversion also reads hexadecimal (0x1F), which numpy refuses
                    if self.int_time and (buf.find(b"0x", 0, cut) >= 0 or buf.find(b"0X", 0, cut) >= 0):
                        raise Fallback("'0x' in the data (pyarrow would read a hexadecimal integer)")
                    # pyarrow skips a byte-order mark at the start of its input; the reference
                    # strips only the file's own (utf-8-sig) and would refuse one elsewhere
                    if buf.startswith(_BOM):
                        raise Fallback("a byte-order mark at the start of a range")
                    if cut:
                        self._put(out, ("data", chunk, nbytes))
            self._put(out, ("end", sha.hexdigest(), nbytes))
        except Fallback as why:
            self._put(out, ("fallback", str(why), 0))
        except Exception as exc:  # noqa: BLE001 - the reference reads the file again and reports it
            self._put(out, ("fallback", f"cannot read: {exc!r}", 0))

    def _put(self, out: queue.Queue, item: tuple) -> None:
        while not self._stop.is_set():
            try:
                out.put(item, timeout=0.1)
                return
            except queue.Full:
                continue

    def batches(self) -> Iterator[list[np.ndarray]]:
        """The chosen columns (in ``usecols`` order) of each range of data lines.

        Raises
        ------
        Fallback
            On anything the fast path does not handle exactly as the reference parser.
        """
        import pyarrow as pa
        import pyarrow.csv as pcsv

        read, parse, convert = self._options()
        chosen = [f"c{j}" for j in self.usecols]
        ranges: queue.Queue = queue.Queue(maxsize=2)
        worker = threading.Thread(target=self._produce, args=(ranges,), name="sigmatau-csv-read", daemon=True)
        worker.start()
        try:
            while True:
                kind, payload, nbytes = ranges.get()
                if kind == "fallback":
                    raise Fallback(payload)
                if kind == "end":
                    self.sha256, self.nbytes = payload, nbytes
                    return
                try:
                    table = pcsv.read_csv(pa.py_buffer(payload), read_options=read, parse_options=parse,
                                          convert_options=convert)
                except (pa.ArrowException, ValueError) as exc:
                    raise Fallback(f"pyarrow: {' '.join(str(exc).split())[:200]}") from None
                del payload
                columns = []
                for k, name in enumerate(chosen):
                    col = table.column(name)
                    if col.null_count:
                        raise Fallback("a missing value")
                    arr = (np.concatenate([c.to_numpy(zero_copy_only=True) for c in col.chunks])
                           if col.num_chunks != 1 else col.chunk(0).to_numpy(zero_copy_only=True))
                    if not (self.int_time and k == 0) and not np.isfinite(arr).all():
                        raise Fallback("a non-finite value (NaN bits and infinity spellings stay the reference's)")
                    columns.append(arr)
                del table
                self.nbytes = nbytes
                yield columns
        finally:
            self._stop.set()
            worker.join()
