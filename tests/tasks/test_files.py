"""Writes into a run folder never leave it: no write through a symbolic link, no ``..``."""

import errno
import os

import pytest

from tasks.core import files


def _tree(folder):
    """Every entry under ``folder`` (links not followed): relative path -> bytes, "dir" or the
    link's target."""
    out = {}
    for dirpath, dirnames, filenames in os.walk(folder):
        for name in dirnames + filenames:
            p = os.path.join(dirpath, name)
            rel = os.path.relpath(p, folder)
            if os.path.islink(p):
                out[rel] = ("link", os.readlink(p))
            elif os.path.isdir(p):
                out[rel] = "dir"
            else:
                with open(p, "rb") as fh:
                    out[rel] = fh.read()
    return out


@pytest.fixture(autouse=True, params=["at-calls", "by-name"])
def platform(request, monkeypatch):
    """Each test with the ``*at`` calls (Linux, macOS) and without (checked by name)."""
    if request.param == "by-name":
        monkeypatch.setattr(files, "_AT_CALLS", False)
    elif not files._AT_CALLS:
        pytest.skip("this platform has no *at calls")


@pytest.fixture
def rooms(tmp_path):
    """A run folder and a folder outside it holding a victim file and an empty folder."""
    run, outside = tmp_path / "run", tmp_path / "outside"
    run.mkdir()
    (outside / "folder").mkdir(parents=True)
    (outside / "victim.png").write_bytes(b"victim")
    return run, outside


def test_a_folder_linked_out_of_the_run_folder_is_refused(rooms):
    run, outside = rooms
    (run / "tables").symlink_to(outside / "folder", target_is_directory=True)
    before = _tree(outside)
    with files.confined(run), pytest.raises(files.LinkInRunFolder) as info:
        files.atomic_write_bytes(run / "tables" / "t.csv", b"a,b\n")
    assert info.value.errno == errno.ELOOP and info.value.filename == str(run / "tables")
    assert "symbolic link inside the run folder" in files.os_error_text(info.value)
    assert _tree(outside) == before
    # deeper: a link among the folders, and a link to a file where a folder belongs
    (run / "data").mkdir()
    (run / "data" / "run-0").symlink_to(outside / "folder", target_is_directory=True)
    (run / "gains").symlink_to(outside / "victim.png")
    with files.confined(run):
        for path in (run / "data" / "run-0" / "x.parquet", run / "gains" / "g.npz"):
            with pytest.raises(files.LinkInRunFolder):
                files.atomic_write_bytes(path, b"x")
        with pytest.raises(files.LinkInRunFolder):
            files.remove(run / "tables" / "t.csv")
        with pytest.raises(files.LinkInRunFolder):
            files.open_for_reading(run / "tables" / "t.csv")
    assert _tree(outside) == before


def test_a_file_linked_out_of_the_run_folder_is_replaced_not_written_through(rooms):
    run, outside = rooms
    (run / "routes.png").symlink_to(outside / "victim.png")
    with files.confined(run):
        files.atomic_write_bytes(run / "routes.png", b"PNG data")
    assert (outside / "victim.png").read_bytes() == b"victim"
    assert not (run / "routes.png").is_symlink()
    assert (run / "routes.png").read_bytes() == b"PNG data"
    # reading does not follow a link either, and removing takes the link, not its target
    (run / "old.png").symlink_to(outside / "victim.png")
    with files.confined(run):
        with pytest.raises(files.LinkInRunFolder):
            files.open_for_reading(run / "old.png")
        files.remove(run / "old.png")
    assert not os.path.lexists(run / "old.png")
    assert (outside / "victim.png").read_bytes() == b"victim"


def test_a_path_leaving_the_run_folder_is_refused(rooms):
    run, outside = rooms
    before = _tree(outside)
    with files.confined(run), pytest.raises(files.LinkInRunFolder, match="leaves the run folder"):
        files.atomic_write_bytes(run / ".." / "outside" / "victim.png", b"x")
    assert _tree(outside) == before


def test_folders_are_made_inside_and_the_run_folder_may_itself_be_a_link(tmp_path):
    real = tmp_path / "real"
    real.mkdir()
    named = tmp_path / "named"  # the folder the user named on the command line
    named.symlink_to(real, target_is_directory=True)
    with files.confined(named):
        files.atomic_write_bytes(named / "data" / "run-000000" / "bauv.parquet", b"p")
        with files.atomic_writer(named / "figure.pdf") as fh:
            fh.write(b"%PDF")
        with files.open_for_reading(named / "figure.pdf") as fh:
            assert fh.read() == b"%PDF"
    assert (real / "data" / "run-000000" / "bauv.parquet").read_bytes() == b"p"
    assert _tree(real) == {
        "data": "dir",
        "data/run-000000": "dir",
        "data/run-000000/bauv.parquet": b"p",
        "figure.pdf": b"%PDF",
    }


def test_a_failed_write_leaves_the_previous_file_and_no_temporary(rooms):
    run, _ = rooms
    (run / "metrics.json").write_bytes(b"old")
    with files.confined(run), pytest.raises(RuntimeError):
        with files.atomic_writer(run / "metrics.json") as fh:
            fh.write(b"half")
            raise RuntimeError("disk full, say")
    assert _tree(run) == {"metrics.json": b"old"}


def test_find_link(rooms):
    run, outside = rooms
    (run / "blocks").mkdir()
    (run / "blocks" / "block-000000.zip").write_bytes(b"z")
    assert files.find_link(run) is None
    (run / "blocks" / "block-000001.zip").symlink_to(outside / "victim.png")
    assert files.find_link(run) == run / "blocks" / "block-000001.zip"
