"""Reading the structured files users give (sweep specs: JSON or TOML; XML), bounded.

:func:`read_structured` refuses, with an :class:`InputError` that names the file
(and the line or entry where it can): a file over MAX_BYTES; text that is not UTF-8
(the line and byte); nesting deeper than MAX_DEPTH; a key given twice in one JSON
object (JSON parsers keep the last silently); an integer of more than MAX_DIGITS
digits (named by its entry).  Every harness command that reads such a file goes
through it, so none can be made to recurse without bound or to allocate without
bound by a file.  XML (URDF, SSP files) is parsed with :func:`xml_parser`.
"""
from __future__ import annotations

import json
import os
import re
import stat
from pathlib import Path
from typing import Any

MAX_BYTES = 1 << 24   # 16 MiB: a spec listing the most runs as points is about 4 MB
MAX_DEPTH = 32        # a spec nests 4 deep
MAX_DIGITS = 1000     # far beyond any 64-bit value (the entry says "out of range"),
                      # far below the 4300 digits Python refuses to convert


class InputError(ValueError):
    """An input (a file or an option's value) cannot be used; the message names it.
    The command line answers it with exit status 2."""


class _BigInteger(str):
    """A JSON integer too long to convert: kept as text so that its entry can be named."""


def read_text(path: str | Path, what: str = "file", limit: int = MAX_BYTES) -> str:
    """The file's UTF-8 text (a BOM dropped); InputError if it cannot be read, is
    larger than ``limit`` bytes or is not UTF-8 (naming the line and byte).  At most
    ``limit`` + 1 bytes are read whatever the file claims: a device such as /dev/zero
    has a size of 0 and no end."""
    path = Path(path)
    try:
        named = os.stat(path).st_mode
        if stat.S_ISFIFO(named) or stat.S_ISSOCK(named):  # opening a pipe waits for a writer
            raise InputError(f"{path}: the {what} is a pipe or a socket, not a file")
        with path.open("rb") as handle:
            mode = os.fstat(handle.fileno()).st_mode
            if stat.S_ISDIR(mode):
                raise InputError(f"{path}: the {what} is a folder, not a file")
            data = handle.read(limit + 1)
    except OSError as error:
        raise InputError(f"{path}: cannot read the {what} ({error.strerror or error})") from None
    if len(data) > limit:
        kind = "" if stat.S_ISREG(mode) else " (it is not a regular file: a device or a pipe)"
        raise InputError(f"{path}: the {what} is larger than {limit} bytes{kind}")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = data.count(b"\n", 0, error.start) + 1
        raise InputError(f"{path} line {line}: byte 0x{data[error.start]:02x} is not UTF-8; "
                         f"save the {what} as UTF-8") from None


def xml_parser(**options: Any):
    """An lxml parser for untrusted XML (URDF, SSV, SSD): no entity expanded, no DTD
    loaded, no network; libxml2's own bounds on depth and sizes stay on."""
    from lxml import etree
    return etree.XMLParser(resolve_entities=False, load_dtd=False, no_network=True,
                           huge_tree=False, **options)


# A TOML string ("...", '...', and their triple-quoted forms) or comment, for the scan below.
_TOML_SKIPPED = re.compile(r'"""(?:[^\\]|\\.)*?"""|\'\'\'.*?\'\'\'|"(?:[^"\\\n]|\\.)*"'
                           r"|'[^'\n]*'|#[^\n]*", re.DOTALL)
# A dotted key of more than MAX_DEPTH parts (a.b.c..., a part bare or a string: "s").
# (MAX_DEPTH dots in a row, each pair apart by one part; tried only where a dot is)
_TOML_DOTTED = re.compile(r"\.(?:[ \t]*[\w-]+[ \t]*\.){" + str(MAX_DEPTH - 1) + ",}")


def check_toml_nesting(text: str) -> str | None:
    """What makes TOML ``text`` nest deeper than MAX_DEPTH, or None: arrays and inline
    tables inside each other, or a dotted key of many parts.  Checked on the text, before
    a TOML parser recurses once per level (RecursionError) or builds a key of n parts n
    times (memory of n^2)."""
    bare = _TOML_SKIPPED.sub(lambda m: "" if m.group(0)[0] == "#" else "s", text)
    depth = deepest = 0
    for char in re.sub(r"[^\[\]{}]+", "", bare):
        if char in "[{":
            depth += 1
            deepest = max(deepest, depth)
            if deepest > MAX_DEPTH:
                break
        elif char in "]}":
            depth = max(0, depth - 1)
    if deepest > MAX_DEPTH:
        return f"arrays or tables nested more than {MAX_DEPTH} deep"
    dotted = _TOML_DOTTED.search(bare)
    if dotted:
        line = bare.count("\n", 0, dotted.start()) + 1
        return f"a dotted key nested more than {MAX_DEPTH} parts deep (line {line})"
    return None


def _object(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    result: dict[str, Any] = {}
    for key, value in pairs:
        if key in result:
            raise InputError(f"the key {key!r} is given twice in one object")
        result[key] = value
    return result


def _integer(text: str) -> int | _BigInteger:
    digits = len(text.lstrip("-"))
    return _BigInteger(text) if digits > MAX_DIGITS else int(text)


def _check(data: Any, path: Path) -> None:
    """Depth and integer sizes, walked without recursion; InputError names the entry."""
    stack: list[tuple[Any, str, int]] = [(data, "", 0)]
    while stack:
        value, where, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise InputError(f"{path}: {where or 'the top level'} is nested more than "
                             f"{MAX_DEPTH} deep")
        if isinstance(value, _BigInteger) or (isinstance(value, int)
                                              and len(str(abs(value))) > MAX_DIGITS):
            raise InputError(f"{path}: {where or 'the value'}: an integer of "
                             f"{len(str(value).lstrip('-'))} digits (at most {MAX_DIGITS})")
        if isinstance(value, dict):
            stack.extend((v, f"{where}.{k}" if where else str(k), depth + 1)
                         for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((v, f"{where}[{i}]", depth + 1) for i, v in enumerate(value))


def read_structured(path: str | Path, what: str = "file") -> Any:
    """The data of a JSON file, or of a TOML file if the name ends in .toml, checked as
    the module describes."""
    path = Path(path)
    text = read_text(path, what)
    if path.suffix == ".toml" and (problem := check_toml_nesting(text)) is not None:
        raise InputError(f"{path}: {problem}")
    try:
        if path.suffix == ".toml":
            import tomllib  # Python >= 3.11
            data = tomllib.loads(text)
        else:
            data = json.loads(text, object_pairs_hook=_object, parse_int=_integer)
    except ImportError:
        raise InputError(f"{path}: TOML needs Python >= 3.11; use JSON") from None
    except InputError as error:
        raise InputError(f"{path}: {error}") from None
    except RecursionError:
        raise InputError(f"{path}: nested more than {MAX_DEPTH} deep") from None
    except ValueError as error:  # JSONDecodeError, TOMLDecodeError, int() of 4300+ digits
        if "digits" in str(error) and "limit" in str(error):
            raise InputError(f"{path}{_long_integer_place(text)}: an integer of more than "
                             f"{MAX_DIGITS} digits") from None
        raise InputError(f"{path}: {error}") from None
    _check(data, path)
    return data


def _long_integer_place(text: str) -> str:
    """' line L (entry KEY)' of the first run of more than MAX_DIGITS digits."""
    match = re.search(rf"\d{{{MAX_DIGITS + 1},}}", text)
    if not match:
        return ""
    line = text.count("\n", 0, match.start()) + 1
    start = text.rfind("\n", 0, match.start()) + 1
    key = text[start:match.start()].split("=")[0].strip()
    return f" line {line}" + (f" (entry {key})" if key else "")
