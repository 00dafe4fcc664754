"""Writes the seed corpus of the fuzz targets into tools/abuse/corpus/.

    .venv/bin/python -m tools.abuse.make_corpus     (from the repository root, after ./build.sh fmus)

fuzz_deserialize/<model>/: valid serialized states of each FMU (after
initialization and after some steps, with identification on for the
observer) in the target's modes 0-3, and forged-field patches (mode 4).  fuzz_calls/: call sequences in
fuzz_calls.c's encoding (a normal life, FMU states, resets, bad values).
The serialized states are valid for the build they came from; for another
build they are still useful seeds (the fuzzer mutates them anyway)."""
from __future__ import annotations

import ctypes
import hashlib
import sys
from pathlib import Path

from tools.abuse.abuse_fmi import MODELS, OK, Raw

ROOT = Path(__file__).resolve().parent

CORPUS = ROOT / "corpus"


def write(folder: Path, data: bytes) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / hashlib.sha1(data).hexdigest()[:16]).write_bytes(data)


def states(model: str) -> list[bytes]:
    per_model: dict[str, dict[str, float]] = {
        "SuperTwistingObserver": {"identifier": 1, "identifier_start": 0},
        "Pendulum": {"damping": 1, "disturbance": 1},
        "TwistingController": {},
        "RobotObserver": {"f_plus[1]": 1000.0, "f_plus[2]": 1000.0},
        "ModelObserver": {"t_id": 0.0}}
    parameters = per_model[model]
    f = Raw(model, "seed")
    assert f.initialize(parameters) == OK, f.messages()
    out = []
    for k in range(200):
        if k in (0, 199):
            state = f.get_state()
            out.append(f.serialize(state))
            f.call("fmi2FreeFMUstate", ctypes.byref(state))
        assert f.do_step(k * 1e-3, 1e-3) == OK
    f.free()
    return out


# fuzz_calls.c: op byte (op % 26), then the op's arguments
SETUP, ENTER, EXIT, STEP, SET_REAL, GET_REAL = 0, 1, 2, 3, 6, 8
SET_INT, SET_BOOL, GET_STATE, SET_STATE, FREE_STATE = 9, 11, 13, 14, 15
SERIALIZE, DESERIALIZE, RESET, TERMINATE, STATUS, NEW = 16, 17, 18, 19, 21, 25


def life() -> list[int]:  # setup(0, 0, 0.0, 0.0, 0.0), enter, exit
    return [SETUP, 0, 0, 0, 0, 0, ENTER, EXIT]


def steps(n: int, how: int = 2) -> list[int]:  # how = 2: H = 1e-3 at the instance's time
    return [STEP, how] * n


CALLS = [
    life() + steps(10),
    life() + [SET_REAL, 1, 0, 5] + steps(5) + [GET_REAL, 8] + list(range(16)),
    life() + steps(3) + [GET_STATE, 0, SERIALIZE, 0, DESERIALIZE, 0, 1] + steps(2) +
    [SET_STATE, 1] + steps(2) + [FREE_STATE, 0, FREE_STATE, 1],
    life() + steps(3) + [GET_STATE, 0, SERIALIZE, 0, DESERIALIZE, 0x21, 0, 0, 0, 90] +
    list(range(8)) + [2, SET_STATE, 2] + steps(2),
    [SET_REAL, 2, 0, 16, 0, 17, ENTER, SETUP, 0, 0, 0, 0, 0, ENTER, EXIT] + steps(3),
    life() + [STEP, 1, 16] + [RESET] + life() + steps(2) + [TERMINATE, TERMINATE, RESET],
    [SET_INT, 1, 1, 3, SET_BOOL, 2, 0, 1, 1, 0] + life() + steps(4, 4) + [STATUS, 2],
    life() + [STEP, 0x81, 12, 3] + steps(2) + [NEW, 0x07] + life() + steps(2),
]


def main(argv: list[str]) -> None:
    into = CORPUS
    if argv[:1] == ["--into"]:
        into, argv = Path(argv[1]), argv[2:]
    for model in argv or MODELS:
        folder = into / "fuzz_deserialize" / model
        for state in states(model):
            write(folder, bytes([0]) + state)
            write(folder, bytes([3]) + state)
            write(folder, bytes([2]) + state[:40])
            write(folder, bytes([1]) + bytes([0, 8, 3, 1, 2, 3]))  # a patch of the payload
        # mode 4, forged fields: (kind, field hi, field lo, element, value) per patch; kind 0
        # the model's field table, 1 the clock, 2 a variable
        for field in range(0, 48, 3):
            write(folder, bytes([4, 0, 0, field, 0, 200 + field % 28]))
        write(folder, bytes([4, 0, 0, 2, 0, 255, 0, 0, 3, 0, 70, 2, 0, 1, 0, 0]))
    for sequence in CALLS:
        write(into / "fuzz_calls", bytes(sequence))
    print(f"seeds in {into}: {sum(1 for p in into.rglob('*') if p.is_file())}")


if __name__ == "__main__":
    main(sys.argv[1:])
