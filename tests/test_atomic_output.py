"""Issue #20 class 1: the atomic writer never destroys what it should not.

Devices and pipes are written directly, symbolic links are written through (and kept), other
non-regular targets are refused; new files honour the umask, replaced files keep their mode;
an output that is an input of the same command is refused by (device, inode); several files of
one run are a transaction that leaves nothing behind when any step fails.
"""

from __future__ import annotations

import os
import socket
import stat
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav import atomicfile
from uasnav.atomicfile import atomic_open, atomic_write_bytes, atomic_write_text, output_set
from uasnav.cli import main
from uasnav.errors import InputError


@pytest.fixture
def umask022():
    old = os.umask(0o022)
    try:
        yield
    finally:
        os.umask(old)


def _run(*args: str):
    return CliRunner().invoke(main, list(args))


def _one_error_line(res) -> str:
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()] if res.stderr else []
    assert res.exit_code == 1, (res.exit_code, res.output)
    assert len(lines) == 1 and lines[0].startswith("error: "), lines
    assert "Traceback" not in res.output
    return lines[0]


@pytest.fixture(scope="module")
def small_log(tmp_path_factory) -> Path:
    p = tmp_path_factory.mktemp("log") / "s.csv"
    res = _run("simulate", "--duration", "3", "--out", str(p))
    assert res.exit_code == 0, res.output
    return p


def _listing(d: Path) -> dict[str, bytes]:
    return {str(p.relative_to(d)): p.read_bytes() for p in sorted(d.rglob("*")) if p.is_file()}


# ---------------------------------------------------------------- permissions


def test_new_file_honours_umask(tmp_path, umask022):
    p = tmp_path / "new.csv"
    atomic_write_text(p, "x\n")
    assert stat.S_IMODE(p.stat().st_mode) == 0o644  # mkstemp alone would give 0600
    os.umask(0o077)
    q = tmp_path / "private.csv"
    atomic_write_text(q, "x\n")
    assert stat.S_IMODE(q.stat().st_mode) == 0o600


def test_replaced_file_keeps_its_mode(tmp_path, umask022):
    p = tmp_path / "old.csv"
    p.write_text("old\n")
    p.chmod(0o640)
    atomic_write_text(p, "new\n")
    assert p.read_text() == "new\n"
    assert stat.S_IMODE(p.stat().st_mode) == 0o640


def test_cli_output_honours_umask(tmp_path, small_log, umask022):
    out = tmp_path / "est.csv"
    res = _run("zupt", str(small_log), "--out", str(out))
    assert res.exit_code == 0, res.output
    assert stat.S_IMODE(out.stat().st_mode) == 0o644


# ---------------------------------------------------- devices, pipes, links


def test_dev_null_is_written_not_replaced(small_log):
    before = os.stat("/dev/null")
    atomic_write_text("/dev/null", "discarded\n")
    res = _run("zupt", str(small_log), "--out", "/dev/null", "--plot", "/dev/null")
    assert res.exit_code == 0, res.output
    after = os.stat("/dev/null")
    assert stat.S_ISCHR(after.st_mode)
    assert (after.st_ino, after.st_rdev) == (before.st_ino, before.st_rdev)


def test_dev_stdout_writes_to_the_open_descriptor(tmp_path):
    # Redirected to a file, /dev/stdout must append at the descriptor's offset, between what
    # the process prints before and after (not replace the file, not rewrite it from offset 0).
    out = tmp_path / "stdout.txt"
    code = (
        "import sys; from uasnav.atomicfile import atomic_write_text; "
        "print('before', flush=True); atomic_write_text('/dev/stdout', 'DATA\\n'); print('after')"
    )
    with open(out, "wb") as fh:
        subprocess.run([sys.executable, "-c", code], stdout=fh, check=True, timeout=60)
    assert out.read_text() == "before\nDATA\nafter\n"


def test_fifo_is_written_directly(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got: list[bytes] = []

    def reader() -> None:
        with open(fifo, "rb") as fh:
            got.append(fh.read())

    t = threading.Thread(target=reader, daemon=True)
    t.start()
    atomic_write_bytes(fifo, b"through the pipe\n")
    t.join(10)
    assert got == [b"through the pipe\n"]
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert [p.name for p in tmp_path.iterdir()] == ["pipe"]  # no temporary file left


def test_symlink_is_written_through_and_kept(tmp_path):
    target = tmp_path / "real.csv"
    target.write_text("old\n")
    target.chmod(0o640)
    link = tmp_path / "link.csv"
    link.symlink_to("real.csv")
    atomic_write_text(link, "new\n")
    assert link.is_symlink() and os.readlink(link) == "real.csv"
    assert target.read_text() == "new\n"
    assert stat.S_IMODE(target.stat().st_mode) == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.csv", "real.csv"]


def test_dangling_symlink_creates_its_target(tmp_path):
    link = tmp_path / "link.csv"
    link.symlink_to("made.csv")
    atomic_write_text(link, "x\n")
    assert link.is_symlink() and (tmp_path / "made.csv").read_text() == "x\n"


def test_directory_and_socket_are_refused(tmp_path):
    d = tmp_path / "adir"
    d.mkdir()
    with pytest.raises(InputError, match="adir: is a directory"):
        atomic_write_text(d, "x")
    with pytest.raises(InputError, match="names a directory"):
        atomic_write_text(f"{tmp_path}/nodir/", "x")
    sock_path = tmp_path / "s.sock"
    s = socket.socket(socket.AF_UNIX)
    try:
        s.bind(str(sock_path))
        with pytest.raises(InputError, match=r"s\.sock: is a socket"):
            atomic_write_text(sock_path, "x")
    finally:
        s.close()
    assert stat.S_ISSOCK(os.lstat(sock_path).st_mode)
    with pytest.raises(InputError, match="empty"):
        atomic_write_text("", "x")


def test_long_file_name_does_not_overflow_the_temporary_name(tmp_path):
    p = tmp_path / ("n" * 250 + ".csv")  # 254 characters: valid, but not with a prefix added
    atomic_write_text(p, "x\n")
    assert p.read_text() == "x\n"


# ------------------------------------------------------ directories, messages


def test_missing_directories_are_created_and_removed_on_failure(tmp_path):
    p = tmp_path / "a" / "b" / "c.csv"
    atomic_write_text(p, "x\n")
    assert p.read_text() == "x\n"
    q = tmp_path / "d" / "e" / "f.csv"
    with pytest.raises(RuntimeError), output_set() as out:
        out.write_text(q, "x\n")
        raise RuntimeError("fail after staging")
    assert not (tmp_path / "d").exists()


def test_errors_name_the_users_path_not_the_temporary_file(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory\n")
    with pytest.raises(OSError) as ei:
        atomic_write_text(blocker / "out.csv", "x")
    assert ".tmp" not in str(ei.value) and str(blocker) in str(ei.value)

    target = tmp_path / "out.csv"

    def deny(src, dst):
        raise PermissionError(13, "Permission denied", src, None, dst)

    monkeypatch.setattr(atomicfile.os, "replace", deny)
    with pytest.raises(PermissionError) as ei:
        atomic_write_text(target, "x")
    assert ei.value.filename == str(target) and ".tmp" not in str(ei.value)
    assert list(tmp_path.iterdir()) == [blocker]


def test_cli_error_names_the_output(tmp_path, small_log):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    line = _one_error_line(_run("zupt", str(small_log), "--out", str(blocker / "est.csv")))
    assert str(blocker) in line and ".tmp" not in line


# ------------------------------------------------------------- transactions


def _prepare(tmp_path: Path) -> tuple[list[Path], dict[str, bytes], dict[str, int]]:
    paths = [tmp_path / "one.csv", tmp_path / "two.csv", tmp_path / "sub" / "three.png"]
    paths[0].write_text("old one\n")
    paths[0].chmod(0o640)
    paths[1].write_text("old two\n")
    inodes = {p.name: p.stat().st_ino for p in paths[:2]}
    return paths, _listing(tmp_path), inodes


@pytest.mark.parametrize("failing", [0, 1, 2])
def test_each_failing_rename_rolls_the_set_back(tmp_path, monkeypatch, failing):
    paths, before, inodes = _prepare(tmp_path)
    real_replace = os.replace
    calls = [0]

    def flaky(src, dst):
        calls[0] += 1
        if calls[0] == failing + 1:
            raise OSError(28, "No space left on device", src)
        return real_replace(src, dst)

    monkeypatch.setattr(atomicfile.os, "replace", flaky)
    with pytest.raises(OSError, match="No space left") as ei, output_set() as out:
        out.write_text(paths[0], "new one\n")
        out.write_text(paths[1], "new two\n")
        out.write_bytes(paths[2], b"new three")
    assert ei.value.filename == str(paths[failing])
    assert _listing(tmp_path) == before  # no temporary, backup or new file; old contents
    assert not (tmp_path / "sub").exists()  # the directory made for three.png is gone
    assert {p.name: p.stat().st_ino for p in paths[:2]} == inodes
    assert stat.S_IMODE(paths[0].stat().st_mode) == 0o640


def test_set_commits_all_files(tmp_path):
    paths, _, _ = _prepare(tmp_path)
    with output_set() as out:
        out.write_text(paths[0], "new one\n")
        with atomic_open(paths[1]) as fh:  # a writer inside the block joins the set
            fh.write("new two\n")
        assert paths[1].read_text() == "old two\n"  # not yet: committed at the end
        out.write_bytes(paths[2], b"new three")
    assert [p.read_bytes() for p in paths] == [b"new one\n", b"new two\n", b"new three"]
    assert stat.S_IMODE(paths[0].stat().st_mode) == 0o640
    assert sorted(_listing(tmp_path)) == ["one.csv", "sub/three.png", "two.csv"]


def test_exception_in_the_block_writes_nothing(tmp_path):
    paths, before, _ = _prepare(tmp_path)
    with pytest.raises(KeyError), output_set() as out:
        out.write_text(paths[0], "new one\n")
        raise KeyError("boom")
    assert _listing(tmp_path) == before


def test_same_file_twice_in_a_set_is_refused(tmp_path):
    p = tmp_path / "x.csv"
    with pytest.raises(InputError, match="written twice"), output_set() as out:
        out.write_text(p, "a")
        out.write_text(tmp_path / "." / "x.csv", "b")
    assert not p.exists()


def test_simulate_cube6_failing_rename_leaves_nothing(tmp_path, monkeypatch):
    old = tmp_path / "c_s0.csv"
    old.write_text("keep me\n")
    real_replace = os.replace
    calls = [0]

    def flaky(src, dst):
        calls[0] += 1
        if calls[0] == 4:
            raise OSError(5, "Input/output error", src)
        return real_replace(src, dst)

    monkeypatch.setattr(atomicfile.os, "replace", flaky)
    line = _one_error_line(
        _run("simulate", "--sensors", "cube6", "--duration", "1", "--out", str(tmp_path / "c.csv"))
    )
    assert "c_s3.csv" in line
    assert _listing(tmp_path) == {"c_s0.csv": b"keep me\n"}


def test_zupt_out_and_plot_roll_back_together(tmp_path, small_log, monkeypatch):
    real_replace = os.replace
    calls = [0]

    def flaky(src, dst):
        calls[0] += 1
        if calls[0] == 2:
            raise OSError(5, "Input/output error", src)
        return real_replace(src, dst)

    monkeypatch.setattr(atomicfile.os, "replace", flaky)
    est, png = tmp_path / "est.csv", tmp_path / "bias.png"
    _one_error_line(_run("zupt", str(small_log), "--out", str(est), "--plot", str(png)))
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------- outputs that are inputs


def _same_input_cases(log: Path, tmp: Path) -> list[list[str]]:
    hard = tmp / "hard.csv"
    if not hard.exists():
        os.link(log, hard)
    sym = tmp / "sym.csv"
    if not sym.exists():
        sym.symlink_to(log)
    other = f"{log.parent}/./{log.name}"
    return [
        ["zupt", str(log), "--out", str(log)],
        ["zupt", str(log), "--out", str(hard)],  # a hard link: another name, same inode
        ["zupt", str(log), "--out", other],  # another spelling
        ["zupt", str(log), "--out", str(sym)],  # a symbolic link to the input
        ["zupt", str(log), "--plot", str(log)],
        ["calibrate", str(log), "--method", "poly", "--out", str(log)],
        ["calibrate", str(log), "--method", "nn", "--out", str(hard)],
        ["redundancy", "fuse", str(log), str(tmp / "b.csv"), "--shape", "aligned", "--out", str(log)],
        ["allan", str(log), "--plot", str(log)],
        ["trajectory", "train", str(log), "--out", str(log)],
        # a preset file (a path, whatever its extension) is an input too
        ["simulate", "--preset", str(tmp / "p.csv"), "--out", str(tmp / "p.csv")],
    ]


def test_output_equal_to_an_input_is_refused(tmp_path):
    log = tmp_path / "in.csv"
    res = _run("simulate", "--duration", "2", "--out", str(log))
    assert res.exit_code == 0, res.output
    (tmp_path / "b.csv").write_bytes(log.read_bytes())
    preset = tmp_path / "p.csv"
    preset.write_text("{}")
    content, inode = log.read_bytes(), log.stat().st_ino
    for args in _same_input_cases(log, tmp_path):
        line = _one_error_line(_run(*args))
        assert "refusing to overwrite an input" in line, (args, line)
        assert log.read_bytes() == content and log.stat().st_ino == inode
    assert preset.read_text() == "{}"


def test_calibrate_both_refuses_a_derived_name_that_is_the_input(tmp_path):
    train = tmp_path / "m.poly.json"
    train.write_text("t,gx\n")
    line = _one_error_line(_run("calibrate", str(train), "--out", str(tmp_path / "m.json")))
    assert "m.poly.json" in line and "input" in line
    assert train.read_text() == "t,gx\n"


def test_two_outputs_naming_one_file_are_refused_before_work(tmp_path, small_log):
    p = tmp_path / "x.out"
    line = _one_error_line(_run("zupt", str(small_log), "--out", str(p), "--plot", str(p)))
    assert "same file" in line
    assert not p.exists()


def test_numbers_unchanged_by_the_writer(tmp_path):
    # the transaction changes how files are placed, never their bytes
    from uasnav.io import read_csv_table, write_csv_table

    p = tmp_path / "t.csv"
    cols = {"t": np.arange(3.0), "v": np.array([1e-3, np.nan, 2.5])}
    with output_set():
        write_csv_table(p, cols)
    got, _ = read_csv_table(p)
    np.testing.assert_array_equal(got["v"], cols["v"])


@pytest.mark.parametrize("failing", [0, 1, 2])
def test_report_files_are_one_transaction(tmp_path, monkeypatch, failing):
    import uasnav.report as report

    def build(w):
        w.data["x"] = 1.0
        w.figures.append(("fake-a.png", b"png bytes"))

    sec = report.Section(key="fake", title="Fake", order=0, build=build)
    monkeypatch.setattr(report, "discover_sections", lambda: [sec])
    out = tmp_path / "rep"
    out.mkdir()
    (out / "report.json").write_text("previous\n")
    before = _listing(tmp_path)
    real_replace = os.replace
    calls = [0]

    def flaky(src, dst):
        calls[0] += 1
        if calls[0] == failing + 1:  # figure, html, json in turn
            raise OSError(28, "No space left on device", src)
        return real_replace(src, dst)

    monkeypatch.setattr(atomicfile.os, "replace", flaky)
    with pytest.raises(OSError, match="No space"):
        report.build_report(out, seed=1, quick=True)
    assert _listing(tmp_path) == before
    assert sorted(p.name for p in out.iterdir()) == ["report.json"]  # figures/ removed again
    monkeypatch.setattr(atomicfile.os, "replace", real_replace)
    res = report.build_report(out, seed=1, quick=True)
    assert res.json_path.read_text() != "previous\n" and (out / "figures" / "fake-a.png").exists()


def test_calibrate_both_writes_both_models_or_neither(tmp_path, monkeypatch):
    t = np.arange(300.0)
    temp = 20.0 + t / 10.0
    gyro = 1e-4 * (temp - 20.0)[:, None] * np.ones(3)
    accel = np.tile([0.0, 0.0, -9.81], (t.size, 1))
    train = tmp_path / "train.csv"
    np.savetxt(
        train,
        np.column_stack([t, gyro, accel, temp]),
        delimiter=",",
        header="t,gx,gy,gz,ax,ay,az,temp",
        comments="",
    )
    old_poly = tmp_path / "m.poly.json"
    old_poly.write_text("previous model\n")
    before = _listing(tmp_path)
    real_replace = os.replace
    calls = [0]

    def flaky(src, dst):
        calls[0] += 1
        if calls[0] == 2:  # the second model's rename
            raise OSError(28, "No space left on device", src)
        return real_replace(src, dst)

    monkeypatch.setattr(atomicfile.os, "replace", flaky)
    line = _one_error_line(
        _run("calibrate", str(train), "--method", "both", "--out", str(tmp_path / "m.json"))
    )
    assert "m.nn.json" in line
    assert _listing(tmp_path) == before
