"""Outputs named like special files: a FIFO, a socket or a device at an output's name (or
behind a link there) is refused with exit status 2 naming it, and is still what it was;
the atomic rename never replaces a node that other programs use.  Real device nodes are
only ever looked at, never written."""
from __future__ import annotations

import os
import socket
import stat
from pathlib import Path

import pytest
from cli_runner import REPO, cli, refused

pytestmark = pytest.mark.cli

EMPS = REPO / "examples" / "emps" / "emps.toml"


@pytest.fixture(scope="module")
def urdf() -> Path:
    from harness.robot.examples import example_urdf
    return Path(example_urdf("double_pendulum")[0])


def fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def still_a_fifo(path: Path) -> bool:
    return stat.S_ISFIFO(os.lstat(path).st_mode)


def test_robot_fmu_parameters_out_a_fifo_is_refused(tmp_path, urdf):
    out = fifo(tmp_path / "robot.ssv")
    code, text = cli(["robot-fmu-parameters", str(urdf), "--out", str(out)])
    assert code == 2, text
    refused(code, text, str(out), "FIFO")
    assert still_a_fifo(out)
    assert [p.name for p in tmp_path.iterdir()] == ["robot.ssv"]  # no staging left


def test_a_link_to_a_fifo_is_refused_not_replaced(tmp_path, urdf):
    node = fifo(tmp_path / "pipe")
    link = tmp_path / "robot.ssv"
    link.symlink_to(node)
    code, text = cli(["robot-fmu-parameters", str(urdf), "--out", str(link)])
    assert code == 2, text
    refused(code, text, "robot.ssv", "FIFO", "link")
    assert link.is_symlink() and still_a_fifo(node)


def test_a_socket_at_the_output_name_is_refused(tmp_path, urdf):
    path = tmp_path / "robot.ssv"
    if len(str(path)) > 100:  # AF_UNIX names are at most 107 bytes
        pytest.skip("temporary folder too deep for a socket name")
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        server.bind(str(path))
        code, text = cli(["robot-fmu-parameters", str(urdf), "--out", str(path)])
        assert code == 2, text
        refused(code, text, "robot.ssv", "socket")
        assert stat.S_ISSOCK(os.lstat(path).st_mode)
    finally:
        server.close()


def test_a_fifo_among_a_folders_outputs_is_refused_before_any_work(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    node = fifo(out / "emps.fmu")  # the name `fmu --model` writes, known in advance
    code, text = cli(["fmu", "--model", str(EMPS), "--out", str(out)])
    assert code == 2, text
    refused(code, text, "emps.fmu", "FIFO")
    assert still_a_fifo(node)
    assert sorted(p.name for p in out.iterdir()) == ["emps.fmu"]


def test_out_a_fifo_for_a_folder_is_refused_naming_it(tmp_path):
    node = fifo(tmp_path / "out")
    code, text = cli(["fmu", "--model", str(EMPS), "--out", str(node)])
    assert code == 2, text
    refused(code, text, "is not a folder", "FIFO")
    assert still_a_fifo(node)


def test_write_atomically_refuses_a_fifo(tmp_path):
    from harness.outputs import OutputError, write_atomically

    node = fifo(tmp_path / "summary.json")
    calls: list[str] = []
    with pytest.raises(OutputError, match="FIFO"):
        write_atomically(node, lambda name: calls.append(name))
    assert still_a_fifo(node) and calls == []  # refused before any work


def test_write_atomically_refuses_a_fifo_made_while_writing(tmp_path):
    from harness.outputs import OutputError, write_atomically

    target = tmp_path / "summary.json"

    def write(name: str) -> None:
        Path(name).write_text("{}")
        os.mkfifo(target)  # another program makes the node while this one writes

    with pytest.raises(OutputError, match="FIFO"):
        write_atomically(target, write)
    assert still_a_fifo(target)
    assert [p.name for p in tmp_path.iterdir()] == ["summary.json"]  # no partial file


def test_devices_are_told_apart_by_a_read_only_look():
    from harness.outputs import special_file

    assert special_file(os.devnull) == "a character device"
    assert special_file(REPO / "README.md") is None
    assert special_file(REPO) is None
