"""Bad input to identify, reproduce and compare, as a user types it.

Every case must end with a clear message naming the problem and a nonzero
exit status -- never a traceback -- and write nothing it should not; the
good cases of the same classes (a BOM, widely spaced samples, epoch
timestamps) must work.

The options of one command path given to another (the robot's unit options without
--robot) are refused too.
"""
from __future__ import annotations

import csv
import time
from pathlib import Path

import numpy as np
import pytest
from cli_runner import REPO, cli, refused

pytestmark = pytest.mark.cli  # the command line, not the FMUs' C code


INT_CASES = ["4294967298", "-4294967294", "2147483648", "-2147483649", "1.5", "2.000001", "nan",
             "inf", "-inf", "1e400", "1e20", "99999999999999999999999"]


def recording(path: Path, t0: float = 0.0, step: float = 1e-3, n: int = 400) -> Path:
    t = t0 + step * np.arange(n)
    y = 0.1 * np.sin(2 * t) + 0.05 * np.sin(7 * t)
    u = np.cos(3 * t)
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", "y", "u"])
        for row in zip(t, y, u):
            w.writerow([repr(float(x)) for x in row])
    return path


@pytest.fixture(scope="module")
def data(tmp_path_factory) -> Path:
    return recording(tmp_path_factory.mktemp("data") / "run.csv")


# ---- integer (and other typed) parameters: never wrapped or truncated -------------------------

@pytest.mark.parametrize("name", ["scheme", "identifier_form", "n", "max_internal_steps"])
@pytest.mark.parametrize("value", INT_CASES + ["0", "-1"])
def test_identify_integer_parameter(tmp_path, data, name, value):
    out = tmp_path / "out"
    code, text = cli(["identify", str(data), "--out", str(out), "--param", f"{name}={value}"])
    refused(code, text, name)
    assert not out.exists(), "refused before anything was written"


@pytest.mark.parametrize("param, words", [
    ("filter_regressor=2", "is not a Boolean"), ("identify_b=0.5", "is not a Boolean"),
    ("tau=nan", "tau = nan is not finite"), ("h=inf", "h = inf is not finite"),
    ("h=-1", "h = -1"), ("rho=1e999", "rho = inf is not finite"),
    ("x1_hat[1]=1", "x1_hat[1] is an output"), ("alpha1_used[1]=1", "calculated parameter"),
    ("nonsense=1", "no variable named 'nonsense'"), ("scheme=abc", "'abc' is not a number"),
    ("=3", "expected NAME=VALUE"), ("scheme", "expected NAME=VALUE"),
])
def test_identify_bad_parameter(tmp_path, data, param, words):
    code, text = cli(["identify", str(data), "--out", str(tmp_path / "o"), "--param", param])
    refused(code, text, words)


def test_identify_integer_in_range_is_recorded_as_an_integer(tmp_path, data):
    out = tmp_path / "out"
    code, text = cli(["identify", str(data), "--out", str(out), "--param", "scheme=2.0",
                      "--param", "max_internal_steps=2147483647"])
    assert code == 0, text
    import json
    saved = json.loads((out / "estimates.json").read_text())["parameters"]
    assert saved["scheme"] == 2 and saved["max_internal_steps"] == 2147483647


# ---- the recording: encodings, binary files, long fields, BOM ------------------------------------

def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


GOOD_ROWS = "".join(f"{k * 1e-3!r},{0.01 * k},{1.0}\n" for k in range(50))
BAD_FILES = {
    "latin1-header": ("t,y,u,temp\u00e9rature\n".encode("latin-1") + GOOD_ROWS.encode(),
                      "is not UTF-8"),
    "latin1-cell": (("t,y,u\n" + GOOD_ROWS).encode() + b"0.5,1,caf\xe9\n", "is not UTF-8"),
    "utf16": (("t,y,u\n" + GOOD_ROWS).encode("utf-16"), "is not UTF-8"),
    "binary-nul": (bytes(range(256)) * 4, None),
    "binary-random": (np.random.default_rng(1).integers(0, 256, 4096, dtype=np.uint8).tobytes(),
                      None),
    "nul-in-row": (("t,y,u\n" + GOOD_ROWS).encode() + b"1\x00,2,3\n", None),
    "huge-field": (("t,y,u\n" + "0," + "1" * 200_000 + ",0\n" + GOOD_ROWS).encode(), None),
    "huge-quoted-field": (('t,y,u\n"' + "x" * 300_000 + '",1,2\n' + GOOD_ROWS).encode(), None),
    "empty": (b"", "the file is empty"),
    "header-only": (b"t,y,u\n", "0 data row(s)"),
    "bom-wrong-columns": (b"\xef\xbb\xbfa,b,c\n1,2,3\n", "missing column(s) t, y, u"),
    "unterminated-quote": (b't,y,u\n"0,1,2\n1,2,3\n', None),
}


@pytest.mark.parametrize("name", list(BAD_FILES))
def test_identify_unreadable_recording(tmp_path, name):
    content, words = BAD_FILES[name]
    path = _write(tmp_path / f"{name}.csv", content)
    code, text = cli(["identify", str(path), "--out", str(tmp_path / "o")])
    refused(code, text, str(path), *([words] if words else []))


@pytest.mark.parametrize("what", ["a-folder", "missing"])
def test_identify_data_path_that_is_no_file(tmp_path, what):
    path = tmp_path if what == "a-folder" else tmp_path / "nothing.csv"
    code, text = cli(["identify", str(path), "--out", str(tmp_path / "o")])
    refused(code, text, "cannot")


@pytest.fixture(scope="module")
def robot_log(tmp_path_factory) -> tuple[Path, Path]:
    """A double pendulum's URDF and a log whose columns have names of their own."""
    from harness.robot.examples import example_urdf
    folder = tmp_path_factory.mktemp("robot")
    t = 1e-3 * np.arange(400)
    rows = np.column_stack([t, np.sin(t), np.cos(t), np.sin(2 * t), np.cos(2 * t)])
    log = folder / "named.csv"
    np.savetxt(log, rows, delimiter=",", header="time,a,b,ta,tb", comments="")
    return Path(example_urdf("double_pendulum")[0]), log


# --columns with a role given twice (the last one won silently: a typo in the first went
# unnoticed) or two roles given one column (one signal read as two, or a shape mismatch
# reported as "line 0: a value is not a number"), on every command that takes it
COLUMN_CASES = {
    "t,y,u role twice": ("tyu", "y=theta,y=y", "--columns gives y twice (y=theta, y=y)"),
    "t,y,u one column": ("tyu", "y=u,u=U", "--columns maps y and u to the same column 'U'"),
    "t,y,u onto a default": ("tyu", "u=y", "y and u are both read from the column 'y'"),
    "robot role twice": ("identify", "q1=zzz,q1=a", "--columns gives q1 twice (q1=zzz, q1=a)"),
    "robot one column": ("identify", "t=time,q1=a,q2=a,u1=ta,u2=tb",
                         "--columns maps q1 and q2 to the same column 'a'"),
    "robot name and number": ("identify", "t=time,q1=2,q2=a,u1=ta,u2=tb",
                              "q1 and q2 are both read from the column 'a'"),
    "validate role twice": ("validate", "t=time,q1=zzz,q1=a",
                            "--columns gives q1 twice (q1=zzz, q1=a)"),
    "validate one column": ("validate", "t=time,q1=b,q2=b,u1=ta,u2=tb",
                            "--columns maps q1 and q2 to the same column 'b'"),
}


@pytest.mark.parametrize("case", list(COLUMN_CASES))
def test_columns_with_a_role_twice_or_a_column_twice_is_refused(tmp_path, data, robot_log,
                                                                case):
    command, columns, words = COLUMN_CASES[case]
    urdf, log = robot_log
    args = (["identify", str(data)] if command == "tyu" else
            [command, str(log), "--robot", str(urdf)])
    code, text = cli([*args, "--columns", columns, "--out", str(tmp_path / "o")])
    assert code == 2, text
    refused(code, text, words)
    assert "line 0" not in text and not (tmp_path / "o").exists()


def test_a_model_file_mapping_two_names_to_one_column_is_refused(tmp_path):
    """The model file's [columns]: the same one reader refuses two names on one column."""
    emps = REPO / "examples" / "emps" / "emps.toml"
    model = tmp_path / "emps.toml"
    model.write_text(emps.read_text().replace('vir = "vir"', 'vir = "qm"'))
    log = tmp_path / "log.csv"
    t = 1e-3 * np.arange(400)
    np.savetxt(log, np.column_stack([t, np.sin(t), np.cos(t)]), delimiter=",",
               header="t,qm,vir", comments="")
    code, text = cli(["identify", str(log), "--model", str(model), "--out", str(tmp_path / "o")])
    assert code == 2, text
    refused(code, text, str(log), "x and vir are both read from the column 'qm'")


@pytest.mark.parametrize("encoding, newline", [("utf-8-sig", "\n"), ("utf-8-sig", "\r\n"),
                                               ("utf-8", "\r\n")])
def test_identify_reads_a_spreadsheet_csv(tmp_path, encoding, newline):
    """What a spreadsheet's "CSV UTF-8" writes: a byte-order mark, CRLF."""
    text = recording(tmp_path / "plain.csv").read_text()
    path = tmp_path / "sheet.csv"
    path.write_bytes(text.replace("\n", newline).encode(encoding))
    code, out = cli(["identify", str(path), "--out", str(tmp_path / "o")])
    assert code == 0, out


# ---- sampling steps the user did not tune h for ----------------------------------------------------

@pytest.mark.parametrize("step", [2.0, 1.5, 10.0, 1.0])
def test_identify_widely_spaced_samples_work(tmp_path, step):
    path = recording(tmp_path / "slow.csv", step=step, n=60)
    out = tmp_path / "o"
    # whole-number stamps 1 s apart look like milliseconds: --time-unit s says they are not
    code, text = cli(["identify", str(path), "--out", str(out), "--time-unit", "s"])
    assert code == 0, text
    assert "h = 2.0 failed" not in text
    import json
    h = json.loads((out / "estimates.json").read_text())["h"]
    assert h <= 1.0 and step / h == round(step / h)
    if step > 1.0:
        assert "largest internal step" in text


def test_identify_h_too_small_for_the_step_work_limit_says_so(tmp_path):
    path = recording(tmp_path / "slow.csv", step=1.0, n=10)
    code, text = cli(["identify", str(path), "--out", str(tmp_path / "o"), "--param", "h=1e-8"])
    refused(code, text, "max_internal_steps")


# ---- full precision -------------------------------------------------------------------------------

@pytest.mark.parametrize("t0, step", [(1.7e9, 1e-3), (1.7e9 + 0.123456789, 1e-3), (0.0, 1e-4),
                                      (-5e8, 2.5e-4)])
def test_identify_writes_times_and_values_at_full_precision(tmp_path, t0, step):
    path = recording(tmp_path / "epoch.csv", t0=t0, step=step, n=3000)
    out = tmp_path / "o"
    code, text = cli(["identify", str(path), "--out", str(out), "--identifier", "off"])
    assert code == 0, text
    with (out / "estimates.csv").open() as f:
        rows = list(csv.DictReader(f))
    times = [float(r["t"]) for r in rows]
    assert len(set(times)) == len(times) == 3000
    with path.open() as f:
        given = [(float(r["t"]), float(r["y"])) for r in csv.DictReader(f)]
    assert [(float(r["t"]), float(r["y"])) for r in rows] == given[:len(rows)]


# ---- --out ------------------------------------------------------------------------------------------

def test_identify_out_naming_a_file_is_refused_before_computing(tmp_path, data):
    target = tmp_path / "estimates.txt"
    target.write_text("keep me")
    start = time.monotonic()
    code, text = cli(["identify", str(data), "--out", str(target)])
    refused(code, text, "exists and is not a folder")
    assert time.monotonic() - start < 5
    assert target.read_text() == "keep me"
    code, text = cli(["identify", str(data), "--out", str(target / "sub")])
    refused(code, text, "cannot create --out")


# ---- reproduce and compare ------------------------------------------------------------------------

@pytest.mark.parametrize("args, words", [
    (["--noise=-1"], "--noise = -1.0 must be >= 0"), (["--noise=nan"], "--noise = nan is not"),
    (["--noise=inf"], "--noise = inf is not finite"), (["--noise", "abc"], "'abc' is not a number"),
    (["--seed=-1"], "--seed = -1 is out of range"), (["--seed", "1.5"], "is not an integer"),
    (["--seed", "nan"], "is not an integer"), (["--seed", str(2**64)], "is out of range"),
    (["--csv-decimation", "0"], "--csv-decimation = 0 is out of range"),
    (["--csv-decimation=-5"], "out of range"), (["--csv-decimation", "2.5"], "not an integer"),
    (["--csv-decimation", "4294967297"], "out of range"),
])
def test_reproduce_bad_option(tmp_path, args, words):
    out = tmp_path / "r"
    code, text = cli(["reproduce", "--scenario", "6.1-sine", "--out", str(out), *args])
    refused(code, text, words)
    assert not out.exists()


@pytest.mark.parametrize("noise, words", [
    ("abc", "'abc' is not a number"), ("-1", "must be >= 0"), ("nan", "is not finite"),
    ("0,,1e-5", "'' is not a number"), ("1e-5,inf", "is not finite"), ("", "is not a number"),
])
def test_compare_bad_noise(tmp_path, noise, words):
    out = tmp_path / "c"
    code, text = cli(["compare", "--scenario", "6.1-sine", "--noise", noise, "--out", str(out)])
    refused(code, text, words)
    assert not out.exists()


def test_reproduce_out_naming_a_file(tmp_path):
    target = tmp_path / "file"
    target.write_text("x")
    code, text = cli(["reproduce", "--scenario", "6.1-sine", "--out", str(target)])
    refused(code, text, "exists and is not a folder")
    assert target.read_text() == "x"


