"""Every message reaches the FMI logger escaped.

The FMI 2 logger reads its message as a printf format in which "#<type><vr>#"
names a variable (FMI 2.0 section 2.1.5); the FMI Library and many C
importers expand it with vsnprintf.  A '%' that the FMU copies unescaped from
a string it was given (a GUID, an instance name, a category, ...) makes such
a logger read arguments that are not there: "%s" or "%n" crash the importer.

The logger here is such an importer: it checks that every '%' and '#' of a
message is doubled, expands the message with libc's snprintf, then '##' to
'#', and records what a user would read.  Each case runs in a forked child
(abuse_fmi.isolated), on the three FMUs, with hostile strings in every place
an importer's string can reach a message.
"""
from __future__ import annotations

import ctypes

import pytest

from tools.abuse.abuse_fmi import (
    ERROR,
    MODELS,
    OK,
    Callbacks,
    Raw,
    assert_usable_after_reset,
    fmi_unescape,
    isolated,
    normal_run,
)

# printf conversions that read or write arguments, FMI variable references, and both doubled.
HOSTILE = ["%s", "%n", "%s%s%s%s%s%s%s%s%n", "%5$s", "%.99999f", "100%", "%", "#", "##", "%%",
           "#r1#", "#i2#x", "{%s-#r120#-%d}", "%\u00e9#"]
LONG = "%" * 3000  # longer than the FMU's message buffer: truncated, never mid-escape

_libc = ctypes.CDLL(None)
_libc.snprintf.restype = ctypes.c_int


class PrintfLogger(Callbacks):
    """An FMI Library-style logger: the message is a printf format (the FMU passes
    no arguments), then "##" is a literal '#'.  A message with a lone '%' is
    recorded as an escaping error and not handed to snprintf (that would be
    undefined behaviour); the others must print as fmi_unescape reads them."""

    def __init__(self):
        super().__init__()
        self.names: list[str] = []

    def _record(self, env, instance, status, category, message):
        raw = message or b""
        text, problem = fmi_unescape(raw.decode("utf-8", errors="replace"))
        self.names.append((instance or b"").decode("utf-8", errors="replace"))
        if problem:
            self.escaping_errors.append(problem)
            self.log.append((status, (category or b"").decode(), text))
            return
        buffer = ctypes.create_string_buffer(8192)
        _libc.snprintf(buffer, ctypes.c_size_t(len(buffer)), ctypes.c_char_p(raw))
        printed = buffer.value.decode("utf-8", errors="replace").replace("##", "#")
        if printed != text:
            self.escaping_errors.append(f"printf shows {printed!r}, not {text!r}")
        self.log.append((status, (category or b"").decode(), printed))


def _fresh(model: str, name: str = "escaping") -> Raw:
    return Raw(model, name, callbacks=PrintfLogger())


def _check(f: Raw, words: str | None = None):
    f.assert_escaped()
    if words is not None:
        assert words in f.messages(), (words, f.messages())


def _wrong_guid(model: str, guid: str):
    f = Raw(model, instantiate=False, callbacks=PrintfLogger())
    pointer = f.instantiate(guid=guid.encode())
    assert not pointer, "a wrong GUID must be refused"
    _check(f, f"GUID mismatch: got {guid[:200]}")
    assert f.cb.log[-1][0] == ERROR


def _instance_name(model: str, name: str):
    """An instance with this name lives a normal life and logs errors escaped;
    the logger gets the name as the instance name, unchanged."""
    f = _fresh(model, name)
    assert f.do_step(0.0, 1e-3) == ERROR  # illegal in Instantiated: a message
    assert_usable_after_reset(f)
    assert f.do_step(5 * 1e-3, -1.0) == ERROR
    _check(f, "communicationStepSize = -1 must be > 0")
    assert set(f.cb.names) == {name}
    # refused at instantiation, with the hostile name and a wrong GUID
    other = f.instantiate(name=name, guid=b"{wrong}")
    assert not other
    _check(f, "GUID mismatch: got {wrong}")
    f.free()


def _resource_location(model: str, location: str):
    f = Raw(model, instantiate=False, callbacks=PrintfLogger())
    f.c = f.instantiate(resources=location.encode())
    if f.reads_resources:  # refused, the location named in the (escaped) message
        assert not f.c
        _check(f, f"cannot open the model file {location.removeprefix('file://')}/model.txt")
        return
    assert f.c, f.messages()
    assert normal_run(f) == [OK] * 6, f.messages()
    assert not f.instantiate(resources=location.encode(), guid=b"{%s#}")
    _check(f, "GUID mismatch: got {%s#}")
    f.free()


def _category(model: str, category: str):
    f = _fresh(model)
    categories = (ctypes.c_char_p * 2)(b"logAll", category.encode())
    assert f.call("fmi2SetDebugLogging", 1, 2, categories) == ERROR
    _check(f, f'unknown log category "{category[:200]}')
    assert_usable_after_reset(f)
    f.free()


def _every_variable_name(model: str):
    """A message naming each variable of the model (a type mismatch), escaped; and
    every out-of-range value for the Integer parameters."""
    f = _fresh(model)
    for variable in f.md.modelVariables:
        wrong = "fmi2SetBoolean" if variable.type != "Boolean" else "fmi2SetReal"
        value = (ctypes.c_int * 1)(1) if wrong == "fmi2SetBoolean" else (ctypes.c_double * 1)(1.0)
        assert f.call(wrong, f.vrs([variable.valueReference]), 1, value) == ERROR
        assert f"{variable.name} (value reference {variable.valueReference})" in f.messages()
        assert f.call("fmi2Reset") == OK
    _check(f)
    f.free()


def _debug_logging_life(model: str):
    """Debug logging on: whatever the FMU says at any level is escaped."""
    f = _fresh(model, "%s#r1#")
    assert f.call("fmi2SetDebugLogging", 1, 0, None) == OK
    assert normal_run(f, steps=20) == [OK] * 21, f.messages()
    assert f.do_step(0.0, 1e-3) == ERROR  # the wrong time
    _check(f, "is not the instance's time")
    f.free()


CASES = []
for m in MODELS:
    for s in HOSTILE + [LONG]:
        CASES.append((f"{m}-guid-{s[:20]!r}", _wrong_guid, m, s))
        CASES.append((f"{m}-category-{s[:20]!r}", _category, m, s))
    for s in HOSTILE:
        CASES.append((f"{m}-instance-name-{s!r}", _instance_name, m, s))
        CASES.append((f"{m}-resource-location-{s!r}", _resource_location, m, "file:///tmp/" + s))
    CASES.append((f"{m}-every-variable-name", _every_variable_name, m, None))
    CASES.append((f"{m}-debug-logging", _debug_logging_life, m, None))


@pytest.mark.parametrize("function, model, text", [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_messages_are_escaped_for_a_printf_style_logger(function, model, text):
    if text is None:
        isolated(function, model)
    else:
        isolated(function, model, text)


def test_the_checker_finds_unescaped_messages():
    """The check itself: a lone '%' or '#' is found, doubled ones are read as one."""
    assert fmi_unescape("100%% of ## x") == ("100% of # x", None)
    assert fmi_unescape("got %s")[1] is not None
    assert fmi_unescape("got #r1#")[1] is not None
    assert fmi_unescape("trailing %")[1] is not None
