"""Names (of files, columns, models) copied into the files the tools generate.

A name may hold any character its file system or its log allows: a newline, a control
character, a lone surrogate (bytes that are not UTF-8).  Copied as it is into a comment,
a resource file or XML, it ends the line (the rest reads as content: other units, other
entries) or makes the file unreadable.  :func:`plain` writes each such character as an
escape, so the copy is one line of printable text.
"""
from __future__ import annotations


def plain(text: str) -> str:
    """``text`` with every character that is not printable (newlines, tabs and other
    controls, line separators, lone surrogates, noncharacters) written as its Python
    escape (``\\n``, ``\\x1b``, ``\\u2028``, ``\\udcff``); printable text unchanged."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
