"""Results written whole or not at all (cosim.engine.files): a disk that cannot take them (full,
read-only) is one line naming what, where and how much space it needed, exit 2; the files that fit
are kept, nothing half-written stands under a final name and no temporary file is left; two runs
into one folder do not mix their files. For `cosim run` (a scene, an SSP system), `export`,
`sweep` and `design`."""

from __future__ import annotations

import csv
import os
import subprocess
import sys

from cosim.cli import main
from cosim.engine.artifacts import ROOT
from conftest import fill

SCENE = ROOT / "scenes" / "meng_eq35.toml"


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err.strip()


def whole(folder) -> None:
    """No temporary file left, and every CSV whole: each line has the header's number of fields."""
    assert not [p.name for p in folder.rglob("*.part")], list(folder.rglob("*"))
    for table in folder.rglob("*.csv"):
        with open(table, newline="") as f:
            lines = list(csv.reader(f))
        assert lines and all(len(line) == len(lines[0]) for line in lines), table


def test_a_run_into_a_full_disk_keeps_what_fits_and_says_what_did_not(small_disk, capsys):
    """Meng's scene for a second (a CSV of about 1 MB, a .mat of about 0.35 MB): with 0.6 MB free the
    CSV does not fit; the .mat and the log are written, the error says so."""
    out = small_disk / "out"
    fill(small_disk, 600_000)
    assert main(["run", str(SCENE), "--duration", "1.0", "--no-plots", "--out", str(out)]) == 2
    err = one_line(capsys)
    assert err.startswith(f"error: the results {out / 'meng_eq35.csv'} could not be written: needs ") and \
        "the disk is full; written: meng_eq35.mat, meng_eq35.log" in err, err
    assert not (out / "meng_eq35.csv").exists() and (out / "meng_eq35.mat").stat().st_size > 300_000
    whole(small_disk)


def test_an_ssp_run_and_a_sweep_into_a_full_disk_are_one_line(small_disk, tmp_path, capsys):
    archive = tmp_path / "meng.ssp"
    assert main(["export", str(SCENE), "--ssp", str(archive)]) == 0
    capsys.readouterr()
    fill(small_disk, 20_000)
    assert main(["run", str(archive), "--duration", "0.2", "--out", str(small_disk / "ssp")]) == 2
    assert "could not be written" in one_line(capsys)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(f'[sweep]\nscene = "{SCENE}"\nduration = 0.05\n[[axis]]\nkey = "scene.step"\nvalues = [5e-4, 1e-3]\n')
    (small_disk / "filler").unlink()
    fill(small_disk, 1_000)
    assert main(["sweep", str(sweep), "--workers", "0", "--out", str(small_disk / "sweep")]) == 2
    assert "the disk is full" in one_line(capsys)
    whole(small_disk)


def test_an_export_into_a_full_or_read_only_folder_is_one_line(small_disk, read_only_disk, capsys):
    fill(small_disk, 100_000)  # the archive, with its FMUs, is several MB
    assert main(["export", str(SCENE), "--ssp", str(small_disk / "meng.ssp")]) == 2
    err = one_line(capsys)
    assert f"the SSP archive {small_disk / 'meng.ssp'} could not be written: needs " in err and "the disk is full" in err
    assert not (small_disk / "meng.ssp").exists()
    whole(small_disk)
    assert main(["export", str(SCENE), "--ssp", str(read_only_disk / "meng.ssp")]) == 2
    assert f"--ssp {read_only_disk}: cannot write results there" in one_line(capsys)
    assert main(["export", str(SCENE), "--osp", str(read_only_disk / "osp")]) == 2
    assert "cannot write results there" in one_line(capsys)


def test_a_design_into_a_full_disk_is_one_line(small_disk, tmp_path, capsys):
    study = tmp_path / "study.toml"
    study.write_text((ROOT / "studies" / "halder_section5.toml").read_text().split("[workspace]")[0].replace(
        "from = 0.80, to = 1.50, step = 0.01", "from = 1.0, to = 1.1, step = 0.05").replace(
        "from = 0.60, to = 1.80, step = 0.01", "from = 1.2, to = 1.4, step = 0.1"))
    fill(small_disk, 50_000)
    assert main(["design", str(study), "--out", str(small_disk / "design")]) == 2
    assert "could not be written" in one_line(capsys)
    whole(small_disk)


def test_two_runs_into_one_folder_do_not_mix(tmp_path, capsys):
    """While a run holds a folder, a second `cosim run` into it is refused in one line before it
    runs; once the first is done, the folder takes the next run."""
    from cosim.engine.files import folder_lock
    out = tmp_path / "out"
    with folder_lock(out):
        second = subprocess.run([sys.executable, "-m", "cosim", "run", str(SCENE), "--duration", "0.05", "--no-plots",
                                 "--out", str(out)], cwd=ROOT, capture_output=True, text=True, timeout=120,
                                env={**os.environ})
        assert second.returncode == 2 and second.stderr.count("\n") == 1, second.stderr
        assert f"{out} is in use by another run (pid {os.getpid()}" in second.stderr
        assert not out.exists()  # the refused run wrote nothing
    assert main(["run", str(SCENE), "--duration", "0.05", "--no-plots", "--out", str(out)]) == 0
    assert (out / "meng_eq35.csv").is_file()
