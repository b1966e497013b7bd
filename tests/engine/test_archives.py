"""SSP archives are read within limits (cosim.engine.archive.unpack): their size in all, their entries
and each entry's unpacked size against its packed size are checked from the archive's directory
before anything is written and again while it unpacks; names that climb out of the folder and
links are refused, naming the entry; nothing unpacked stays behind, refused or run; a full disk is
named as one."""

from __future__ import annotations

import gc
import os
import subprocess
import sys
import zipfile

import pytest

from cosim.engine.artifacts import ROOT
from cosim.engine.archive import ArchiveLimits, unpack
from cosim.engine.ssp import SspError, read_ssp, write_ssp
from test_coupling import oscillator


@pytest.fixture
def temporary(tmp_path, monkeypatch):
    """The temporary folder this test's unpacking goes to (and whose leftovers it counts)."""
    import tempfile
    folder = tmp_path / "temporary"
    folder.mkdir()
    monkeypatch.setenv("TMPDIR", str(folder))
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    return folder


@pytest.fixture(scope="module")
def system_archive(tmp_path_factory):
    return write_ssp(oscillator(0.5), tmp_path_factory.mktemp("archive") / "oscillator.ssp")


def archive_with(path, entries: dict[str, bytes], base=None):
    """A copy of `base` (or an empty archive) with more entries."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as out:
        if base is not None:
            with zipfile.ZipFile(base) as source:
                for info in source.infolist():
                    out.writestr(info, source.read(info))
        for name, data in entries.items():
            out.writestr(name, data)
    return path


def test_a_bomb_is_refused_from_its_directory_before_anything_is_written(tmp_path, temporary, system_archive):
    bomb = archive_with(tmp_path / "bomb.ssp", {"resources/zeros.bin": bytes(50 << 20)}, system_archive)
    assert bomb.stat().st_size < 1 << 20  # 50 MB of zeros pack to about 50 kB
    with pytest.raises(SspError, match=r"'resources/zeros.bin' unpacks to 52.4 MB, \d+ times its packed size"):
        read_ssp(bomb)
    assert list(temporary.iterdir()) == []  # nothing written, nothing left


def test_the_limits_hold_in_all_and_are_settable(tmp_path, temporary, system_archive, monkeypatch):
    big = archive_with(tmp_path / "big.ssp", {"resources/data.bin": os.urandom(3 << 20)}, system_archive)
    monkeypatch.setenv("COSIM_SSP_MAX_BYTES", str(2e6))
    with pytest.raises(SspError, match=r"unpacks to \d+\.\d MB; an SSP archive may unpack to 2.0 MB \(COSIM_SSP_MAX_BYTES\)"):
        read_ssp(big)
    monkeypatch.setenv("COSIM_SSP_MAX_BYTES", str(1e9))
    monkeypatch.setenv("COSIM_SSP_MAX_ENTRIES", "3")
    with pytest.raises(SspError, match=r"\d entries; an SSP archive may hold 3 \(COSIM_SSP_MAX_ENTRIES\)"):
        read_ssp(big)
    monkeypatch.delenv("COSIM_SSP_MAX_ENTRIES")
    assert read_ssp(big).name  # within the limits again
    gc.collect()
    assert [p for p in temporary.iterdir() if p.name.startswith("cosim-ssp-")] == []  # gone with the system read


@pytest.mark.parametrize("name,message", [("../outside.txt", "climbs out"), ("/etc/outside.txt", "climbs out"),
                                          ("resources/../../outside.txt", "climbs out")])
def test_names_that_climb_out_are_refused_naming_the_entry(tmp_path, temporary, system_archive, name, message):
    path = tmp_path / "climbing.ssp"
    with zipfile.ZipFile(path, "w") as out:
        with zipfile.ZipFile(system_archive) as source:
            for info in source.infolist():
                out.writestr(info, source.read(info))
        out.writestr(zipfile.ZipInfo(name), b"planted")  # ZipInfo keeps the name as given
    with pytest.raises(SspError, match=f"entry {name!r} {message}"):
        read_ssp(path)
    assert not (tmp_path / "outside.txt").exists() and list(temporary.iterdir()) == []


def test_a_link_in_an_archive_is_refused(tmp_path, temporary, system_archive):
    link = zipfile.ZipInfo("resources/link")
    link.external_attr = (0o120777 << 16)  # a symbolic link
    path = tmp_path / "link.ssp"
    with zipfile.ZipFile(path, "w") as out:
        with zipfile.ZipFile(system_archive) as source:
            for info in source.infolist():
                out.writestr(info, source.read(info))
        out.writestr(link, "/etc/passwd")
    with pytest.raises(SspError, match="entry 'resources/link' is a link: refused"):
        read_ssp(path)


def test_no_run_of_an_archive_leaves_its_unpacked_copy(tmp_path, system_archive):
    """`cosim run FILE.ssp` to its end, and one refused at its settings: the temporary folder holds
    nothing afterwards."""
    temporary = tmp_path / "temporary"
    temporary.mkdir()
    env = {**os.environ, "TMPDIR": str(temporary)}
    for extra, code in (([], 0), (["--set", "bogus=1"], 2)):
        run = subprocess.run([sys.executable, "-m", "cosim", "run", str(system_archive), "--out", str(tmp_path / "out"),
                              *extra], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
        assert run.returncode == code, run.stderr
        assert [p.name for p in temporary.iterdir() if p.name.startswith("cosim-ssp-")] == []


def test_the_unpacked_files_go_with_the_system_that_holds_them(temporary, system_archive):
    system = read_ssp(system_archive)
    folder = system.components[0].fmu.parent
    assert folder.is_dir() and str(folder).startswith(str(temporary))
    del system
    gc.collect()
    assert not folder.exists()


@pytest.mark.parametrize("left", [0.5, 1.2], ids=["too little to unpack", "too little to read the FMUs"])
def test_a_full_disk_is_named_as_one(small_disk, system_archive, monkeypatch, left):
    """A temporary folder with less free space than the archive unpacks to (refused before
    unpacking), or than unpacking and reading its FMUs take: named as a full disk, nothing left."""
    import shutil
    import tempfile
    monkeypatch.setattr(tempfile, "tempdir", str(small_disk))
    with zipfile.ZipFile(system_archive) as archive:
        needed = sum(e.file_size for e in archive.infolist())
    (small_disk / "filler").write_bytes(bytes(shutil.disk_usage(small_disk).free - int(left * needed)))
    with pytest.raises(SspError, match="the disk is full") as refused:
        read_ssp(system_archive)
    assert "damaged" not in str(refused.value)
    gc.collect()
    assert [p.name for p in small_disk.iterdir() if p.name.startswith("cosim-ssp-")] == []
