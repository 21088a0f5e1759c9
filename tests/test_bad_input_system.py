"""Stale inputs rebuilt, system errors named, valid logs read (issue 35, items 5-7).

- A recording replaced by another (an older copy, ``cp -p``) makes ingest run again:
  the recording's files' sizes and modification times go through the rule's ``params:``
  (:func:`floorscan.core.files.recording_fingerprint`).
- No space left, a read-only file system, permission denied: one paragraph naming the
  path and what to do, no traceback (:func:`floorscan.core.stage.stage_log`,
  :func:`floorscan.core.messages.system_error_message`); a results folder that cannot
  be written stops the run before any job (``workflow/rules/common.smk``).
- A message quotes at most 200 characters of the user's data.
- A CARMEN log is known by its line types, not only by a laser line among its first
  lines; a gzip log with trailing garbage is read with a warning, as ``gzip -d`` does.
"""

from __future__ import annotations

import errno
import gzip
import logging
import os
import re
import shutil
import subprocess
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from conftest import copy_workflow, flaser_line, snakemake, write_bag, write_carmen
from floorscan.core.files import atomic_path, recording_fingerprint, writable_problem
from floorscan.core.io import InputError
from floorscan.core.messages import MAX_QUOTE, quoted, shorten_message
from floorscan.core.stage import failure_message, stage_log
from floorscan.ingest.detect import detect_format
from floorscan.ingest.readers import open_recording
from floorscan.ingest.text import open_text

IS_ROOT = hasattr(os, "geteuid") and os.geteuid() == 0


def _carmen_log(path: Path, n_scans: int = 30, radius: float = 2.0, t0: float = 10.0, before=()) -> Path:
    """A CARMEN log: the ``before`` lines, then ``n_scans`` FLASER lines of a robot
    driving along +x in a round room of ``radius`` metres."""
    lines = list(before)
    for i in range(n_scans):
        r = radius + 0.3 * np.sin(np.linspace(0.0, 6.0, 180) + 0.1 * i)
        lines.append(flaser_line(r, (0.05 * i, 0.0, 0.01 * i), t0 + 0.2 * i))
    return write_carmen(path, lines)


def _smk(tmp_path: Path, rule="ingest", inputs=(), outputs=(), log=True):
    return SimpleNamespace(
        rule=rule, log=[str(tmp_path / f"{rule}.log")] if log else [], wildcards={"dataset": "lab"},
        input=list(inputs), output=list(outputs),
    )


def _errors(log: Path) -> list[str]:
    return [line for line in log.read_text().splitlines() if " ERROR " in line]


# --- stale input (item 5) ---------------------------------------------------------------


def test_the_fingerprint_follows_the_content_not_the_age(tmp_path):
    log = _carmen_log(tmp_path / "a.log")
    first = recording_fingerprint(log)
    assert first == recording_fingerprint(log)  # the same file: the same params, no rerun
    assert first["files"] == 1 and first["bytes"] == log.stat().st_size
    other = _carmen_log(tmp_path / "b.log", radius=3.0)
    shutil.copy2(other, log)  # cp -p: another recording, and older than the first
    os.utime(log, ns=(1_500_000_000_000_000_000, 1_500_000_000_000_000_000))
    assert recording_fingerprint(log) != first
    # a folder (a PCD folder, a ROS2 bag): any of its files
    folder = tmp_path / "pcd"
    (folder / "sub").mkdir(parents=True)
    for name in ("0000.pcd", "0001.pcd", "sub/locations.csv"):
        (folder / name).write_text(name)
    before = recording_fingerprint(folder)
    assert before["files"] == 3
    stat = (folder / "0001.pcd").stat()
    (folder / "0001.pcd").write_text("0001.pcX")  # same size, content changed ...
    os.utime(folder / "0001.pcd", ns=(stat.st_atime_ns, stat.st_mtime_ns - 10**9))  # ... and older
    assert recording_fingerprint(folder) != before
    assert recording_fingerprint(tmp_path / "missing.bag") is None


def _pcd_folder(folder: Path, shift: float) -> Path:
    """A PCD folder of three ascii scans and its locations.csv; ``shift`` moves the points."""
    folder.mkdir(parents=True, exist_ok=True)
    rows = ["file,t_ns,x,y,z,yaw"]
    angles = np.linspace(0.0, 2 * np.pi, 90, endpoint=False)
    for i in range(3):
        pts = np.c_[(2.0 + shift) * np.cos(angles) + i, (2.0 + shift) * np.sin(angles), np.full(90, 0.4)]
        body = "\n".join(f"{x:.4f} {y:.4f} {z:.4f}" for x, y, z in pts)
        (folder / f"{i:04d}.pcd").write_text(
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            f"WIDTH 90\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 90\nDATA ascii\n{body}\n"
        )
        rows.append(f"{i:04d}.pcd,{1000 + 100 * i},{i},0,0.4,0")
    (folder / "locations.csv").write_text("\n".join(rows) + "\n")
    return folder


def _replace_with_older(src: Path, dst: Path) -> None:
    """Put ``src`` in place of ``dst`` (a file or folder), dated a year before ``dst``'s outputs."""
    old = 1_600_000_000_000_000_000
    if dst.is_dir():
        shutil.rmtree(dst)
        shutil.copytree(src, dst)
        for p in [*dst.rglob("*"), dst]:
            os.utime(p, ns=(old, old))
    else:
        shutil.copy2(src, dst)
        os.utime(dst, ns=(old, old))


@pytest.mark.workflow
def test_ingest_reruns_when_the_recording_is_replaced_by_an_older_copy(tmp_path):
    """Before: "Nothing to be done" and the old tables kept, as the replacement is older
    than them. After: ingest runs again and its tables hold the new recording."""
    wd = copy_workflow(tmp_path / "floorscan")
    log = _carmen_log(tmp_path / "lab.log", radius=2.0)
    pcd = _pcd_folder(tmp_path / "room", shift=0.0)
    cases = {
        "lab": (log, _carmen_log(tmp_path / "other.log", radius=3.0)),
        "room": (pcd, _pcd_folder(tmp_path / "other_room", shift=1.0)),
    }
    for name, (recording, replacement) in cases.items():
        target = f"results/{name}/scans.parquet"
        args = ("--config", f"path={recording}", "--", target)
        res = snakemake(wd, *args, timeout=300)
        assert res.returncode == 0, res.stderr[-3000:]
        before = pd.read_parquet(wd / target)
        res = snakemake(wd, *args, timeout=300)
        assert res.returncode == 0 and "Nothing to be done" in res.stdout + res.stderr, name
        _replace_with_older(replacement, recording)
        assert recording.stat().st_mtime < (wd / target).stat().st_mtime  # older than its tables
        res = snakemake(wd, *args, timeout=300)
        out = res.stdout + res.stderr
        assert res.returncode == 0, out[-3000:]
        assert "Rule: ingest" in out and "Params have changed" in out, (name, out[-3000:])
        after = pd.read_parquet(wd / target)
        # the tables hold the replacement: its points are farther from the scanner
        r_before = np.hypot(before["x"], before["y"]).mean()
        r_after = np.hypot(after["x"], after["y"]).mean()
        assert r_after > r_before + 0.5, (name, r_before, r_after)


# --- system errors (item 6) -------------------------------------------------------------

PYARROW_ENOSPC = "Error writing bytes to file. Detail: [errno 28] No space left on device"


def test_no_space_inside_a_stage_is_one_paragraph_naming_the_output(tmp_path, capsys):
    """A full disk while writing an output (pyarrow's OSError names no file): the
    paragraph names the output atomic_path was writing, with what to do."""
    out = tmp_path / "results" / "lab" / "scans.parquet"
    with pytest.raises(SystemExit) as exit_info:
        with stage_log(_smk(tmp_path, outputs=[out])):
            with atomic_path(out):
                raise OSError(errno.ENOSPC, PYARROW_ENOSPC)
    assert exit_info.value.code == 1
    text = (tmp_path / "ingest.log").read_text()
    assert "Traceback" not in text and "Traceback" not in capsys.readouterr().err
    (error,) = _errors(tmp_path / "ingest.log")
    assert f"ingest failed: no space left on the device holding {out}: free some space there" in error
    assert f"df -h {out.parent}" in error
    assert not list(out.parent.iterdir())  # no temporary left


def test_a_real_full_device_names_the_outputs_folder(tmp_path, capsys):
    """A write to /dev/full (a device that is always full) fails with ENOSPC as a full
    disk does; the OSError names no file, so the paragraph names the job's outputs."""
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full on this system")
    outputs = [tmp_path / "results" / "lab" / "a.parquet", tmp_path / "results" / "lab" / "b.parquet"]
    with pytest.raises(SystemExit):
        with stage_log(_smk(tmp_path, outputs=outputs)):
            with open("/dev/full", "wb") as f:
                f.write(b"x" * 100_000)
    (error,) = _errors(tmp_path / "ingest.log")
    assert f"no space left on the device holding {tmp_path / 'results' / 'lab'}:" in error
    assert "Traceback" not in (tmp_path / "ingest.log").read_text() + capsys.readouterr().err


def test_a_log_file_on_a_full_disk_leaves_the_paragraph_on_stderr(tmp_path, capsys):
    """The log file cannot take the failure either (it is on the full disk): the
    paragraph goes to stderr, once, without logging's own traceback."""
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full on this system")
    smk = SimpleNamespace(rule="ingest", log=["/dev/full"], wildcards={}, input=[], output=[str(tmp_path / "x")])
    with pytest.raises(SystemExit):
        with stage_log(smk):
            raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "x"))
    err = capsys.readouterr().err
    assert err.count("ingest failed: no space left on the device holding") == 1, err
    assert "Traceback" not in err and "Logging error" not in err


def test_read_only_and_permission_denied_name_the_path(tmp_path, capsys):
    recording = tmp_path / "data" / "lab.bag"
    out = tmp_path / "results" / "lab" / "scans.parquet"
    cases = {
        OSError(errno.EROFS, "Read-only file system", str(out.parent)):
            f"{out.parent} is on a read-only file system: run the workflow where results/ can be written",
        PermissionError(errno.EACCES, "Permission denied", str(recording)):
            f"permission denied reading {recording}: give your user read access to it",
        PermissionError(errno.EPERM, "Operation not permitted", str(out)):
            f"permission denied writing {out}: give your user write access to it",
    }
    for error, expected in cases.items():
        with pytest.raises(SystemExit) as exit_info:
            with stage_log(_smk(tmp_path, inputs=[recording], outputs=[out])):
                raise error
        assert exit_info.value.code == 1 and exit_info.value.__cause__ is error
        (line,) = _errors(tmp_path / "ingest.log")
        assert expected in line, line
        assert "Traceback" not in (tmp_path / "ingest.log").read_text() + capsys.readouterr().err


def test_a_reader_that_wraps_permission_denied_is_not_called_corrupt(tmp_path, capsys):
    """A reader's "cannot read the log, truncated or corrupt" raised while handling a
    PermissionError (``raise InputError(...) from None`` keeps it as the context)."""
    recording = tmp_path / "lab.log"
    with pytest.raises(SystemExit):
        with stage_log(_smk(tmp_path, inputs=[recording])):
            try:
                raise PermissionError(errno.EACCES, "Permission denied", str(recording))
            except OSError as e:
                raise InputError(f"{recording}: cannot read the log, truncated or corrupt ({e})") from None
    (line,) = _errors(tmp_path / "ingest.log")
    assert f"ingest failed: permission denied reading {recording}: give your user read access" in line
    assert "corrupt" not in line


def test_other_os_errors_are_still_bugs_with_their_traceback(tmp_path):
    with pytest.raises(FileNotFoundError):
        with stage_log(_smk(tmp_path)):
            open(tmp_path / "nowhere" / "x")
    assert "Traceback" in (tmp_path / "ingest.log").read_text()


@pytest.mark.skipif(IS_ROOT, reason="running as root: chmod cannot make a folder unwritable for root")
def test_an_unwritable_results_folder_is_found_before_any_job(tmp_path):
    results = tmp_path / "results"
    results.mkdir()
    assert writable_problem(results) is None
    results.chmod(0o555)
    try:
        problem = writable_problem(results)
    finally:
        results.chmod(0o755)
    assert problem is not None and problem.startswith(f"permission denied writing {results}:")


@pytest.mark.skipif(IS_ROOT, reason="running as root: chmod cannot take read access away from root")
def test_an_unreadable_recording_is_permission_denied_not_corrupt(tmp_path):
    log = _carmen_log(tmp_path / "lab.log")
    log.chmod(0)
    try:
        with pytest.raises(PermissionError):
            detect_format(log)
    finally:
        log.chmod(0o644)


def _namespaces_work() -> bool:
    """Whether this process may mount in a private mount namespace (``unshare -m``)."""
    if not shutil.which("unshare") or not IS_ROOT:
        return False
    res = subprocess.run(["unshare", "-m", "true"], capture_output=True)
    return res.returncode == 0


needs_mounts = pytest.mark.skipif(
    not _namespaces_work(), reason="needs root and `unshare -m` to mount a read-only or full results folder"
)


def _run_in_namespace(wd: Path, mount: str, recording: Path) -> subprocess.CompletedProcess:
    """snakemake (the ingest target of ``recording``) with ``mount`` (a shell command) run
    first in a private mount namespace: the test machine's mounts are not touched."""
    from conftest import SNAKEMAKE

    script = f"{mount} && cd {wd} && {SNAKEMAKE} --cores 2 --config path={recording} -- results/lab/scans.parquet"
    return subprocess.run(["unshare", "-m", "sh", "-c", script], capture_output=True, text=True, timeout=300)


@needs_mounts
@pytest.mark.workflow
def test_a_read_only_results_folder_stops_the_run_with_one_line(tmp_path):
    """Before: Snakemake's "Failed to create output directory" (a read-only results/) or
    its own traceback (a read-only working folder: it cannot make .snakemake/)."""
    log = _carmen_log(tmp_path / "lab.log")
    wd = copy_workflow(tmp_path / "floorscan")
    (wd / "results").mkdir()
    for folder in (wd / "results", wd):
        res = _run_in_namespace(wd, f"mount --bind -o ro {folder} {folder}", log)
        out = res.stdout + res.stderr
        assert res.returncode == 1, out[-3000:]
        lines = [line for line in out.splitlines() if line.startswith("Cannot run:")]
        assert lines == [
            f"Cannot run: {wd / 'results'} is on a read-only file system: run the workflow where results/ can "
            "be written (a copy of the workflow, or results/ as a symbolic link to a writable disk), or remount "
            "the disk read-write, then run again ([Errno 30] Read-only file system)"
        ], out[-3000:]
        assert "Traceback" not in out


@needs_mounts
@pytest.mark.workflow
def test_a_full_results_disk_fails_the_stage_with_one_paragraph(tmp_path):
    """results/ on a 64 kB disk: the ingest job fails on its first table with one
    paragraph naming it (before: the traceback of pyarrow, naming no path)."""
    log = _carmen_log(tmp_path / "lab.log", n_scans=200)
    wd = copy_workflow(tmp_path / "floorscan")
    (wd / "profiles").symlink_to("workflow/profiles")  # the default profile prints a failed job's log
    (wd / "results").mkdir()
    res = _run_in_namespace(wd, f"mount -t tmpfs -o size=64k tmpfs {wd / 'results'}", log)
    out = res.stdout + res.stderr
    assert res.returncode == 1, out[-3000:]
    lines = [line for line in out.splitlines() if "ingest failed:" in line]
    assert len(lines) == 1, out[-3000:]
    assert re.search(r"ingest failed: no space left on the device holding results/lab/\S+\.parquet: ", lines[0])
    assert "Traceback" not in out


# --- the user's data quoted short (item 6) ----------------------------------------------


def test_quoted_user_data_is_cut_to_200_characters():
    line = "\x00\x01binary" * 100_000  # a line of a binary file read as text
    q = quoted(line)
    assert q.startswith(repr(line[:MAX_QUOTE])[:-1]) and q.endswith("…' (800,000 characters)")
    assert quoted("/scan") == "'/scan'"
    # a message that quoted a line whole (the CARMEN reader given a ROS1 bag printed
    # 831,111 characters): cut in the paragraph of the stage
    message = failure_message("ingest", InputError(f"/data/x.bag:3: malformed FLASER line: field 2 is {line!r}"))
    assert len(message) < 1200
    assert max(len(run) for run in re.findall(r"\S+", message)) <= MAX_QUOTE + len("…(2,400,002 characters)")
    assert message.startswith("ingest failed: /data/x.bag:3: malformed FLASER line: field 2 is")
    # floorscan's own messages are left whole
    own = "ingest failed: /data/lab.bag: no topic '/scan' for scans; topics in the bag: '/tf', '/odom'"
    assert shorten_message(own) == own


def test_a_bag_read_as_a_carmen_log_gives_a_short_message(tmp_path):
    """`format: carmen` given on a .bag: the paragraph quotes little of its binary."""
    bag = write_bag(tmp_path / "lab.bag")
    with pytest.raises(InputError) as info:
        open_recording({"format": "carmen", "path": str(bag), "name": "lab"}, {}, max_gap_s=0.5)
    message = failure_message("ingest", info.value)
    assert str(bag) in message
    assert len(message) <= 1200, len(message)


def test_detection_quotes_at_most_40_characters_of_a_word(tmp_path):
    odd = tmp_path / "run.log"
    odd.write_text("X" * 5000 + " 1 2 3\n" + "GET /index.html 200\n" * 5)
    with pytest.raises(InputError) as info:
        detect_format(odd)
    message = str(info.value)
    assert "'" + "X" * 40 + "…' (5,000 characters)" in message and "X" * 41 not in message
    assert "'GET'" in message and "not a CARMEN log" in message


# --- format detection (item 7) ----------------------------------------------------------


def test_a_carmen_log_with_25000_lines_before_its_first_laser_line_is_read(tmp_path):
    """Before: "no FLASER or ROBOTLASER1 line in its first 20000 lines, so not a CARMEN
    log floorscan reads". Its lines are CARMEN messages: it is one."""
    odom = [f"ODOM {0.001 * k:.3f} 0 0 0 0 0 {1.0 + 0.0003 * k:.4f} host {1.0 + 0.0003 * k:.4f}" for k in range(25_000)]
    log = _carmen_log(tmp_path / "late.log", n_scans=20, before=["PARAM robot_name pioneer 0 host 0", *odom])
    assert detect_format(log) == "carmen"
    rec = open_recording({"path": str(log), "name": "late"}, {}, max_gap_s=0.5)
    assert len(list(rec.scans)) == 20
    # a .log of other lines is still refused
    server = write_carmen(tmp_path / "server.log", ["GET /index.html 200"] * 30_000 + [flaser_line([1.0] * 180, (0, 0, 0), 1.0)])
    with pytest.raises(InputError, match="server.log: no FLASER or ROBOTLASER1 line in its first 20000 lines, and 20000 of them"):
        detect_format(server)


def test_a_byte_order_mark_before_the_only_laser_line(tmp_path):
    """The first line is the laser line (an editor added the mark): still a CARMEN log."""
    log = tmp_path / "bom.log"
    log.write_bytes(b"\xef\xbb\xbf" + flaser_line([1.0] * 180, (0.0, 0.0, 0.0), 1.0).encode() + b"\n")
    assert detect_format(log) == "carmen"
    with open_text(log) as f:
        assert f.readline().startswith("FLASER 180 ")


def _with_trailing_garbage(path: Path, garbage: bytes = b"\x00\x00junk appended by a copy tool\n" * 4) -> bytes:
    data = path.read_bytes()
    path.write_bytes(data + garbage)
    return garbage


def test_gzip_with_trailing_garbage_reads_as_gzip_d_does(tmp_path):
    log = _carmen_log(tmp_path / "lab.log.gz", n_scans=12)
    text = gzip.decompress(log.read_bytes()).decode()
    garbage = _with_trailing_garbage(log)
    res = subprocess.run(["gzip", "-dc", str(log)], capture_output=True) if shutil.which("gzip") else None
    if res is not None:  # what gzip -d does: the data, and a warning
        assert res.stdout.decode() == text and b"trailing garbage ignored" in res.stderr
    notes: list[str] = []
    with open_text(log, notes) as f:
        assert f.read() == text
    assert notes == [
        f"{log}: {len(garbage)} bytes of trailing garbage after the gzip data ignored (as gzip -d does); "
        "the log was read up to them"
    ]
    assert detect_format(log) == "carmen"
    # a truncated gzip is still an error
    cut = tmp_path / "cut.log.gz"
    cut.write_bytes(gzip.compress(text.encode())[:-30])
    with pytest.raises(EOFError):
        with open_text(cut) as f:
            f.read()


def test_a_carmen_gzip_with_trailing_garbage_is_ingested_with_a_warning(tmp_path, caplog):
    """Before: "cannot read the log, truncated or corrupt (Not a gzipped file)"."""
    log = _carmen_log(tmp_path / "lab.log.gz", n_scans=12)
    _with_trailing_garbage(log)
    with caplog.at_level(logging.WARNING):
        rec = open_recording({"path": str(log), "name": "lab"}, {}, max_gap_s=0.5)
        n_scans = len(list(rec.scans))
    assert n_scans == 12
    said = [r.getMessage() for r in caplog.records] + list(rec.notes)
    assert any("trailing garbage after the gzip data ignored" in s for s in said), said
