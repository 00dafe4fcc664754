"""Reading a recorded experiment (time, position, input) for identification.

A recording is a CSV file with a header row, or a Parquet file (told by the extension,
harness.log_columns.log_format: any other is refused).  Three of its columns are used:
the time stamps ``t``, the measured position ``y`` and the applied input
``u``; ``columns`` maps them to the file's own names (``{"t": "time", "y":
"theta", "u": "tau"}``; by default ``t`` or ``time``, ``y``, ``u``, any case).

Time stamps may be in any unit (``time_unit``, converted by pint: harness.units, as
every log's) and start anywhere (epoch
seconds included): inside, time runs from 0 at the first sample, in seconds; the
stamps themselves are kept as written for the outputs.  Samples must be
uniformly spaced within ``tolerance`` (a fraction of the step, default 1 %:
clock jitter of a logger); anything else is refused unless ``resample`` puts the
recording on a uniform grid first (linear interpolation of y; u held or
interpolated, see :func:`harness.identify.held_input`).

Long logs are read in blocks of whole lines, each parsed by pyarrow's CSV
reader (a Parquet file: in row batches, by pyarrow): memory does not grow with the
length of the file.  A file the fast
reader refuses is read again by a careful line-by-line parser
(:func:`_exact_error`) only to name the line and the problem.
"""
from __future__ import annotations

import csv
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .units import TIME_UNITS

if TYPE_CHECKING:
    import pyarrow as pa

DEFAULT_TOLERANCE = 0.01  # of the sampling step
BLOCK_BYTES = 1 << 20  # 1 MB of CSV text per block (about 2 10^4 rows of t, y, u)
# --resample fills gaps of at most this many grid steps (a longer one would be made-up
# data, and a gap of 10^6 s at 1 kHz alone is 10^9 rows); the grid is made in pieces of
# GRID_PIECE points, so memory stays that of a block whatever the gaps
MAX_GAP_STEPS = 1000
GRID_PIECE = 1 << 16


class DataError(ValueError):
    """The recorded data cannot be used; the message names the file and line."""


@dataclass
class Recording:
    """A recording in memory: time stamps [s] (as given), positions, inputs."""

    t: np.ndarray
    y: np.ndarray
    u: np.ndarray

    @property
    def step(self) -> float:
        return float(self.t[1] - self.t[0])


@dataclass
class ReadOptions:
    """How to read a recording (see the module documentation)."""

    columns: Mapping[str, str] = field(default_factory=dict)  # "t"/"y"/"u" -> file's name
    time_unit: str | None = None  # None: seconds, checked for a likely other unit
    tolerance: float = DEFAULT_TOLERANCE  # allowed deviation of a step, fraction of the step
    resample: float | None = None  # None: no; 0: to the median step; > 0: to this step [s]


@dataclass
class Block:
    """Consecutive samples: the stamps as written (text), time since the first
    sample [s], position and input."""

    stamps: pa.StringArray  # pyarrow strings: written out unchanged
    time: np.ndarray
    y: np.ndarray
    u: np.ndarray


def parse_columns(text: str) -> dict[str, str]:
    """``t=time,y=theta,u=tau`` -> {"t": "time", "y": "theta", "u": "tau"}."""
    mapping: dict[str, str] = {}
    for item in filter(None, (part.strip() for part in text.split(","))):
        role, sep, name = item.partition("=")
        role = role.strip()
        if not sep or role not in ("t", "y", "u") or not name.strip():
            raise DataError(f"--columns {text!r}: expected ROLE=NAME items with ROLE one of t, "
                            f"y, u (e.g. t=time,y=theta,u=tau), got {item!r}")
        mapping[role] = name.strip()
    return mapping


def _header(path: Path) -> list[str]:
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            reader = csv.reader(handle)
            header = next(reader, None)
    except OSError as error:
        raise DataError(f"{path}: cannot open ({error.strerror or error})") from None
    except UnicodeDecodeError:
        raise DataError(f"{path}: {_not_utf8(path)}; identify reads UTF-8 text (save the file "
                        f"as CSV UTF-8)") from None
    except csv.Error as error:
        raise DataError(f"{path} line 1: not a readable CSV file ({error}); identify needs "
                        f"a text CSV with a header naming t, y, u") from None
    if header is None:
        raise DataError(f"{path}: the file is empty")
    return header


def _locate(path: Path, header: list[str], columns: Mapping[str, str]) -> dict[str, int]:
    """role -> index of its column in the header (names compared without case)."""
    names = [h.strip().lower() for h in header]
    found: dict[str, int] = {}
    missing = []
    for role in ("t", "y", "u"):
        wanted = [columns[role]] if role in columns else (["t", "time"] if role == "t"
                                                          else [role])
        index = next((names.index(w.strip().lower()) for w in wanted
                      if w.strip().lower() in names), None)
        if index is None:
            missing.append(columns.get(role, role))
            continue
        found[role] = index
    if missing:
        raise DataError(f"{path} line 1: missing column(s) {', '.join(missing)}; the header "
                        f"must name t (or time), y and u, or map them with --columns "
                        f"t=NAME,y=NAME,u=NAME (found: {', '.join(header) or 'nothing'})")
    from .log_columns import LogColumnError, check_distinct_columns
    try:  # "u=y": u mapped onto the column y is read from
        check_distinct_columns(f"{path} line 1", header, list(found.items()),
                               key=lambda name: name.strip().lower())
    except LogColumnError as error:
        raise DataError(f"{error} (--columns t=NAME,y=NAME,u=NAME maps the roles)") from None
    return found


def read_blocks(path: str | Path, options: ReadOptions | None = None) -> Iterator[Block]:
    """The recording's samples in blocks, checked (finite numbers, time increasing and
    uniformly spaced within the tolerance, or resampled); DataError names the line."""
    options = options or ReadOptions()
    path = Path(path)
    if options.time_unit is not None and options.time_unit not in TIME_UNITS:
        raise DataError(f"time unit {options.time_unit!r}: expected one of "
                        f"{', '.join(TIME_UNITS)}")
    if not (math.isfinite(options.tolerance) and options.tolerance >= 0):
        raise DataError(f"time tolerance {options.tolerance!r}: expected a number >= 0")
    if path.is_dir():
        raise DataError(f"{path}: cannot read a folder as a recording")
    from .log_columns import LogColumnError, log_format
    from .log_columns import read_header as read_table_header
    try:
        parquet = log_format(path) == "parquet"
        header = list(read_table_header(path)) if parquet else _header(path)
    except LogColumnError as error:
        raise DataError(str(error)) from None
    index = _locate(path, header, options.columns)
    if parquet:
        blocks = _parquet_blocks(path, header, index, options)
        checked = _checked(path, blocks, options, place=("row", 0))
    else:
        checked = _checked(path, _fast_blocks(path, header, index, options), options)
    if options.resample is not None:
        return _resampled(checked, options.resample, _scale(options))
    return checked


def _line_blocks(path: Path, size: int) -> Iterator[bytes]:
    """The file's bytes in blocks of whole lines: each block is what is left of the
    previous one after its last newline plus the next ``size`` bytes, cut after its last
    newline (the blocks of pyarrow's streaming reader).  Read here one at a time: that
    reader reads up to 32 blocks ahead of a slow consumer (128 MB at 4 MB a block)."""
    rest = b""
    with path.open("rb") as handle:
        while chunk := handle.read(size):
            text = rest + chunk
            end = text.rfind(b"\n") + 1
            if end:
                rest = text[end:]
                yield text[:end]
            else:
                rest = text
    if rest:
        yield rest


def _fast_blocks(path: Path, header: list[str], index: dict[str, int], options: ReadOptions
                 ) -> Iterator[tuple[pa.StringArray, np.ndarray, np.ndarray, np.ndarray,
                                     np.ndarray]]:
    """(stamps as text, stamps as numbers, stamps since the first one, y, u) blocks parsed
    by pyarrow; any complaint of pyarrow (or a value that is missing or not finite) is
    turned into the exact message by _exact_error."""
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.csv as pacsv

    names = [f"c{i}" for i in range(len(header))]
    wanted = {role: names[i] for role, i in index.items()}
    convert = pacsv.ConvertOptions(
        include_columns=list(dict.fromkeys(wanted.values())),
        column_types={wanted["t"]: pa.string(), wanted["y"]: pa.float64(),
                      wanted["u"]: pa.float64()})
    origin = None
    try:
        for number, text in enumerate(_line_blocks(path, BLOCK_BYTES)):
            table = pacsv.read_csv(pa.py_buffer(text), read_options=pacsv.ReadOptions(
                column_names=names, skip_rows=1 if number == 0 else 0,
                block_size=len(text) + 1, use_threads=False), convert_options=convert)
            if not table.num_rows:
                continue
            stamps = pc.utf8_trim_whitespace(table.column(wanted["t"]).combine_chunks())
            y = _doubles(table.column(wanted["y"]))
            u = _doubles(table.column(wanted["u"]))
            values = _doubles(pc.cast(stamps, pa.float64()))
            if not (np.isfinite(values).all() and np.isfinite(y).all()
                    and np.isfinite(u).all()):
                raise _exact_error(path, index, options)
            since, origin = _since_first(stamps, values, origin)
            yield stamps, values, since, y, u
    except (pa.ArrowInvalid, UnicodeDecodeError, pa.ArrowException):
        raise _exact_error(path, index, options) from None
    except OSError as error:
        raise DataError(f"{path}: cannot read ({error.strerror or error})") from None


def _doubles(column: pa.Array | pa.ChunkedArray) -> np.ndarray:
    """A float64 column's values, NaN where one is missing (as pyarrow's to_numpy gives
    them, which loads pandas: 50 MB and a third of a second that a CSV log needs not)."""
    import pyarrow as pa
    import pyarrow.compute as pc

    array = column.combine_chunks() if isinstance(column, pa.ChunkedArray) else column
    if array.null_count:
        array = pc.fill_null(array, math.nan)
    if not len(array):
        return np.empty(0)
    return np.frombuffer(array.buffers()[1], dtype=np.float64, count=len(array),
                         offset=8 * array.offset)


def _since_first(stamps: pa.StringArray, values: np.ndarray, origin):
    """The stamps minus the first stamp of the file, computed from the text in decimal
    arithmetic where it fits (epoch stamps keep their sub-microsecond digits, which a
    double of 1.7e9 s has not); else from the doubles.  ``origin`` is the first stamp
    (a decimal scalar, a float, or None for the first block)."""
    import pyarrow as pa
    import pyarrow.compute as pc

    exact = pa.decimal128(37, 18)  # 19 digits before the point, 18 after
    if origin is None or isinstance(origin, pa.Scalar):
        try:
            decimals = pc.cast(stamps, exact)
            origin = decimals[0] if origin is None else origin
            since = pc.cast(pc.subtract(decimals, origin), pa.float64())
            return _doubles(since), origin
        except pa.ArrowInvalid:  # more digits than that, or exponents out of range
            if origin is not None:
                origin = float(origin.as_py())
    origin = float(values[0]) if origin is None else origin
    return values - origin, origin


def _parquet_blocks(path: Path, header: list[str], index: dict[str, int],
                    options: ReadOptions) -> Iterator[tuple[pa.StringArray, np.ndarray,
                                                            np.ndarray, np.ndarray,
                                                            np.ndarray]]:
    """The blocks of _fast_blocks from a Parquet file's row batches: the stamps as text
    (pyarrow's shortest decimal of each number), a value that is missing or not finite
    named with its row."""
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.parquet as pq

    wanted = {role: header[i] for role, i in index.items()}
    origin = None
    rows = 0
    try:
        source = pq.ParquetFile(path)
        for role, column in wanted.items():
            kind = source.schema_arrow.field(column).type
            if not (pa.types.is_integer(kind) or pa.types.is_floating(kind)
                    or pa.types.is_decimal(kind)):
                raise DataError(f"{path}: column {column!r} ({role}) holds {kind}, not "
                                "numbers (time stamps too must be numbers, e.g. seconds)")
        for batch in source.iter_batches(batch_size=BLOCK_BYTES // 64,
                                         columns=list(dict.fromkeys(wanted.values()))):
            time = batch.column(wanted["t"])
            stamps = pc.cast(time, pa.string())
            values, y, u = (pc.cast(batch.column(wanted[role]), pa.float64())
                            .to_numpy(zero_copy_only=False) for role in ("t", "y", "u"))
            bad = ~(np.isfinite(values) & np.isfinite(y) & np.isfinite(u))
            if bad.any():
                k = int(np.argmax(bad))
                role = next(r for r, v in (("t", values), ("y", y), ("u", u))
                            if not np.isfinite(v[k]))
                raise DataError(f"{path} row {rows + k + 1}: {wanted[role]} is missing or not "
                                "finite (NaN or Inf rows must be removed or interpolated "
                                "first)")
            if not batch.num_rows:
                continue
            since, origin = _since_first(stamps, values, origin)
            rows += batch.num_rows
            yield stamps, values, since, y, u
    except (pa.ArrowException, OSError) as error:
        raise DataError(f"{path}: not a readable Parquet file ({error})") from None
    if rows < 3:
        raise DataError(f"{path}: {rows} data row(s); at least 3 are needed")


def _scale(options: ReadOptions) -> float:
    """Seconds per unit of the time column (pint's factor, harness.units); seconds
    without pint (loading it takes half a second and 20 MB)."""
    if options.time_unit in (None, "s"):
        return 1.0
    from .units import factor
    return factor(options.time_unit, "s")


def _checked(path: Path, blocks, options: ReadOptions,
             place: tuple[str, int] = ("line", 1)) -> Iterator[Block]:
    """The blocks checked; `place`: what a message calls a row of the file and how many
    lines come before the first data row (a CSV file's header line; 0 in Parquet)."""
    word, before_data = place
    scale = _scale(options)
    step = None
    previous = None  # the last time [s] of the previous block, relative
    rows = 0
    for stamps, values, since, y, u in blocks:
        if not len(stamps):
            continue
        time = since * scale
        joined = time if previous is None else np.concatenate([[previous], time])
        dt = np.diff(joined)
        first_line = rows + 1 + before_data - (previous is not None)  # joined[0]'s line
        if dt.size and not (dt > 0).all():
            i = int(np.argmin(dt > 0))
            k = first_line + i - (rows + 1 + before_data)  # this block's index of the earlier
            before = stamps[k].as_py() if k >= 0 else "the previous block's last"
            raise DataError(f"{path} {word} {first_line + i + 1}: time does not increase "
                            f"(t = {before}, then {stamps[k + 1].as_py()})")
        if step is None and dt.size:
            step = float(np.median(dt[: 1000]))
            if options.time_unit is None and step >= 1.0 and np.all(values[:1000] % 1 == 0):
                from .messages import note

                note(f"{path}: whole-number time stamps {step:g} apart, taken as seconds: "
                     f"if they are milliseconds (or us, ns), give --time-unit ms; "
                     f"--time-unit s confirms seconds")
        if options.resample is not None and step is not None and dt.size:
            grid = options.resample if options.resample > 0 else step  # [s]
            wide = np.nonzero(dt > MAX_GAP_STEPS * grid)[0]
            if wide.size:
                i = int(wide[0])
                raise DataError(
                    f"{path} {word} {first_line + i + 1}: a gap of {dt[i]:.9g} s in the time "
                    f"stamps, {dt[i] / grid:.3g} steps of the --resample grid ({grid:g} s); "
                    f"--resample fills gaps of at most {MAX_GAP_STEPS} steps: split the log "
                    f"at the gap")
        if options.resample is None and step is not None and dt.size:
            # a step may deviate by the tolerance (jitter) and by rounding of the stamps
            slack = options.tolerance * step + 8 * np.finfo(float).eps * np.abs(
                values[0] * scale + joined[1:])
            bad = np.nonzero(np.abs(dt - step) > slack)[0]
            if bad.size:
                i, unit = int(bad[0]), options.time_unit or "s"
                raise DataError(
                    f"{path} {word} {first_line + i + 1}: sampling step {dt[i] / scale:.9g} "
                    f"{unit} differs from the step {step / scale:.9g} "
                    f"{unit} by more than the tolerance "
                    f"({100 * options.tolerance:g} % of the step); identify needs uniform "
                    f"sampling: raise --time-tolerance, or --resample onto a uniform grid")
        previous = float(time[-1])
        rows += len(stamps)
        yield Block(stamps, time, y, u)
    if rows < 3:
        raise DataError(f"{path}: {rows} data row(s); at least 3 are needed")


def _resampled(blocks: Iterator[Block], step: float, scale: float) -> Iterator[Block]:
    """The blocks on the uniform grid k * step [s] (step 0: the median step of the first
    block): y interpolated linearly, u the last sample at or before each grid time (a
    command holds until the next one), stamps first stamp + k * step in the file's unit."""
    import pyarrow as pa

    carry: Block | None = None
    k = 0  # the next grid point
    first = None  # the first stamp, in the file's unit
    for block in blocks:
        if first is None:
            first = float(block.stamps[0].as_py())
            if not step > 0:
                step = float(np.median(np.diff(block.time[:1001])))
        if carry is not None:
            block = Block(pa.concat_arrays([carry.stamps[-1:], block.stamps]),
                          np.concatenate([carry.time[-1:], block.time]),
                          np.concatenate([carry.y[-1:], block.y]),
                          np.concatenate([carry.u[-1:], block.u]))
        last = int(np.floor(block.time[-1] / step + 1e-9))
        carry = block
        for start in range(k, last + 1, GRID_PIECE):
            grid = np.arange(start, min(start + GRID_PIECE, last + 1)) * step
            held = np.searchsorted(block.time, grid, side="right") - 1
            stamps = pa.array([repr(float(first + g / scale)) for g in grid], pa.string())
            yield Block(stamps, grid, np.interp(grid, block.time, block.y), block.u[held])
        k = max(k, last + 1)


def read_recording(path: str | Path, options: ReadOptions | None = None) -> Recording:
    """The whole recording in memory (for short logs and scripts); the time stamps are
    seconds from the first sample plus the first stamp (in seconds)."""
    options = options or ReadOptions()
    import pyarrow as pa

    blocks = list(read_blocks(path, options))
    scale = _scale(options)
    if options.resample is None:  # the stamps as written, in seconds
        t = np.concatenate([b.stamps.cast(pa.float64()).to_numpy(zero_copy_only=False)
                            for b in blocks]) * scale
    else:
        t = float(blocks[0].stamps[0].as_py()) * scale + np.concatenate([b.time
                                                                          for b in blocks])
    return Recording(t, np.concatenate([b.y for b in blocks]),
                     np.concatenate([b.u for b in blocks]))


# ---- the careful parser, for messages -----------------------------------------------------

def _exact_error(path: Path, index: dict[str, int], options: ReadOptions) -> DataError:
    """The first problem of the file, with its line, found by reading it line by line."""
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            reader = csv.reader(handle)
            rows = 0
            try:
                next(reader, None)
                for row in reader:
                    line = reader.line_num
                    if not row or all(not cell.strip() for cell in row):
                        continue
                    rows += 1
                    for role in ("t", "y", "u"):
                        i = index[role]
                        name = options.columns.get(role, role)
                        if i >= len(row):
                            return DataError(f"{path} line {line}: column {name!r} is missing "
                                             f"({len(row)} fields)")
                        text = row[i].strip()
                        try:
                            value = float(text)
                        except ValueError:
                            return DataError(f"{path} line {line}: {name} = {text!r} is not "
                                             f"a number")
                        if not math.isfinite(value):
                            return DataError(f"{path} line {line}: {name} = {text} is not "
                                             f"finite (NaN or Inf rows must be removed or "
                                             f"interpolated first)")
            except csv.Error as error:
                return DataError(f"{path} line {reader.line_num}: not a readable CSV file "
                                 f"({error}); identify needs a text CSV with a header naming "
                                 f"t, y, u")
    except UnicodeDecodeError:
        return DataError(f"{path}: {_not_utf8(path)}; identify reads UTF-8 text (save the "
                         f"file as CSV UTF-8)")
    except OSError as error:
        return DataError(f"{path}: cannot read ({error.strerror or error})")
    if rows < 3:
        return DataError(f"{path}: {rows} data row(s); at least 3 are needed")
    return DataError(f"{path}: not a readable CSV file; identify needs a text CSV with a "
                     f"header naming t, y, u")


def _not_utf8(path: Path) -> str:
    """Where the file stops being UTF-8: its first bad byte, with line and offset."""
    data = path.read_bytes()
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as error:
        line = data.count(b"\n", 0, error.start) + 1
        return (f"line {line}: byte 0x{data[error.start]:02x} at offset {error.start} is not "
                f"UTF-8")
    return "not UTF-8"
