"""The files a user writes, under hostile edits: seeded mutations of every shipped scene, every
shipped sweep file, the Meng scene's exported SSP archive and its SSD and SSV, a trajectory table
(CSV) a scene reads, a vehicle's motion (CSV) and the scene that takes it through the cueing, each
run briefly through every command of the CLI that reads it (a scene: run, export, view,
stream-layout; a sweep file: sweep; an archive: run, export-check; a vehicle's motion and its
scene: run, tune; a study: design), asserting that it ends with exit 0 (ran), 1 (a run that
failed, with its report) or 2 (one line: the file, the place, what and why), never with a
traceback, an exit 3 or a hang. And the places they are read from and written to: hostile
archives (bombs, names that climb out, links, thousands of entries: nothing unpacked may stay
behind or land outside), a disk filled to a random level before a run, an export, a sweep or a
design writes to it (no half-written file under a final name, no temporary file left), and a
sweep's cache with planted files or the wrong owner or mode (a planted file is never run: the rows
are the sweep's own); and a design study (`cosim design`), where a numpy warning that leaks is a
violation too.

    .venv/bin/python tests/fuzz/fuzz_inputs.py                     CI: seed 1 and a new seed (printed),
                                                                  --mutants per file kind and seed (default 40)
    .venv/bin/python tests/fuzz/fuzz_inputs.py --long              10 000 mutants per file kind (seed 1)
    .venv/bin/python tests/fuzz/fuzz_inputs.py --replay KIND SEED INDEX    one mutant: its diff and all it printed

A mutation is one of: a value replaced by a hostile one (0, a negative, 1e300, 1e-300, nan, inf,
text, a boolean, an empty list or table, a string where a number stood), a line deleted,
duplicated or swapped with another, a name misspelt, the file cut short (an archive: a byte
changed, bytes cut out, or cut short; or a hostile entry added). The disk kind mounts a tmpfs of a
few MB per slot (it needs root, and says so where it cannot). Each mutant runs in a
forked child of this process (the modules and FMUs loaded once), two at a time, with a time limit.
Exits 1 on any violation, each printed with its one-line replay.
"""

from __future__ import annotations

import argparse
import difflib
import io
import os
import random
import re
import shutil
import signal
import sys
import tempfile
import time
import zipfile
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from cosim.cli import main  # noqa: E402

HOSTILE = ["0", "-1", "-0.0", "1e300", "-1e300", "1e-300", "nan", "inf", "-inf", '"text"', '""', "true", "false",
           "[]", "{}", "[1, 2]", '"neutral"', "3.5", "1e12"]
HOSTILE_XML = ["0", "-1", "1e300", "1e-300", "nan", "inf", "-inf", "text", "", "true", "leg[0].angle", "pmsm9",
               "resources/nothing.fmu", "0.5", "1e12", "&amp;"]
TIME_LIMIT = 60.0  # [s] per mutant: a brief run takes well under a second
BINARY = ("ssp", "archive")  # kinds whose file is bytes (held as latin-1 text)


@dataclass
class Base:
    kind: str        # scene, sweep, ssd, ssv, table, ssp, archive, disk, cache, study, vehicle, cueing
    name: str | None  # the mutant's path in the work tree (beside the files it refers to); None: no file
    text: str        # the unmutated file
    command: list    # the CLI call; {root} is the work tree, {out} the output folder, {disk} the small disk


def _brief_sweep(text: str) -> str:
    """A shipped sweep file made brief: its runs 5 ms long, each axis cut to two values."""
    text = re.sub(r"(?m)^duration\s*=.*$", "duration = 0.005", text)
    return re.sub(r"(?m)^(values\s*=\s*\[)([^,\]]+),\s*([^,\]]+)(,[^\]]*)?\]", r"\1\2, \3]", text)


def bases(root: Path) -> dict[str, list[Base]]:
    """The unmutated files of each kind, in a work tree `root` with what they refer to: the
    shipped scenes and sweep files, and the Meng scene's exported SSP unpacked."""
    shutil.copytree(ROOT / "scenes", root / "scenes")
    shutil.copytree(ROOT / "sweeps", root / "sweeps")
    out: dict[str, list[Base]] = {"scene": [], "sweep": [], "ssd": [], "ssv": [], "table": [], "ssp": [],
                                  "archive": [], "disk": [], "cache": [], "study": [], "vehicle": [], "cueing": []}
    scene_commands = (["run", "{root}/scenes/mutant.toml", "--duration", "0.02", "--no-plots", "--out", "{out}"],
                      ["export", "{root}/scenes/mutant.toml", "--ssp", "{out}/mutant.ssp", "--scene-step"],
                      ["view", "{root}/scenes/mutant.toml", "--out", "{out}"],
                      ["stream-layout", "{root}/scenes/mutant.toml"])
    for path in sorted((root / "scenes").glob("*.toml")):  # every scene through every command that reads one
        for command in scene_commands:
            out["scene"].append(Base("scene", "scenes/mutant.toml", path.read_text(), command))
    for path in sorted((root / "sweeps").glob("*.toml")):
        out["sweep"].append(Base("sweep", "sweeps/mutant.toml", _brief_sweep(path.read_text()),
                                 ["sweep", "{root}/sweeps/mutant.toml", "--workers", "0", "--out", "{out}"]))
    archive = root / "meng.ssp"
    with _quiet():
        assert main(["export", str(ROOT / "scenes" / "meng_eq35.toml"), "--ssp", str(archive), "--scene-step"]) == 0
    with zipfile.ZipFile(archive) as z:
        z.extractall(root / "ssp")
    for command in (["run", "{root}/meng.ssp", "--duration", "0.02", "--out", "{out}"],
                    ["export-check", "{root}/meng.ssp", "--dry-run"]):
        out["ssp"].append(Base("ssp", "meng.ssp", archive.read_bytes().decode("latin-1"), command))
    ssd = root / "ssp" / "SystemStructure.ssd"
    out["ssd"].append(Base("ssd", "ssp/mutant.ssd", ssd.read_text(),
                           ["run", "{root}/ssp/mutant.ssd", "--duration", "0.02", "--out", "{out}"]))
    for ssv in sorted((root / "ssp" / "resources").glob("*.ssv")):
        # the mutant SSV stands in for the original beside the unchanged SSD (restored after each run)
        out["ssv"].append(Base("ssv", f"ssp/resources/{ssv.name}", ssv.read_text(),
                               ["run", "{root}/ssp/SystemStructure.ssd", "--duration", "0.02", "--out", "{out}"]))
    # a trajectory table (heave and roll over 1 s) read by a scene that adds it to its signals
    t = [k / 50 for k in range(51)]
    (root / "scenes" / "table.csv").write_text("time,z,roll\n" + "".join(
        f"{x!r},{0.05 * x * (1 - x)!r},{0.01 * x!r}\n" for x in t))
    (root / "scenes" / "with_table.toml").write_text(
        '[scene]\nduration = 0.02\n[trajectory]\ntable = "table.csv"\ninterpolation = "linear"\n'
        '[trajectory.z]\noffset = "neutral"\n')
    out["table"].append(Base("table", "scenes/table.csv", (root / "scenes" / "table.csv").read_text(),
                             ["run", "{root}/scenes/with_table.toml", "--no-plots", "--out", "{out}"]))
    out["archive"].append(Base("archive", "hostile.ssp", archive.read_bytes().decode("latin-1"),
                               ["run", "{root}/hostile.ssp", "--duration", "0.02", "--out", "{out}"]))
    (root / "sweeps" / "brief.toml").write_text(
        f'[sweep]\nscene = "{root}/scenes/meng_eq35.toml"\nduration = 0.02\n[[axis]]\nkey = "scene.step"\n'
        'values = [5e-4, 1e-3]\n')
    (root / "studies").mkdir()
    tiny = (ROOT / "studies" / "halder_section5.toml").read_text().split("[workspace]")[0].replace(
        "from = 0.80, to = 1.50, step = 0.01", "from = 1.0, to = 1.1, step = 0.05").replace(
        "from = 0.60, to = 1.80, step = 0.01", "from = 1.2, to = 1.4, step = 0.1") + \
        "[thresholds]\ncondition_number = 20\nsingular_distance_factor = 2\n"
    (root / "studies" / "tiny.toml").write_text(tiny)
    out["study"].append(Base("study", "studies/mutant.toml", tiny, ["design", "{root}/studies/mutant.toml", "--out",
                                                                    "{out}"]))
    # a vehicle's motion (examples/vehicle) and the scene that takes it through the cueing, briefly, each
    # through run and tune (a search of one generation of one point, in this process)
    drive = (ROOT / "examples" / "vehicle" / "drive.csv").read_text().split("\n")
    (root / "scenes" / "drive.csv").write_text("\n".join(drive[:2 + 40]) + "\n")  # its first 0.4 s
    car = (ROOT / "examples" / "vehicle" / "car_drive.toml").read_text().replace("duration = 20.0", "duration = 0.3")
    car += "\n[cueing.tune]\niterations = 1\npopulation = 1\n"
    (root / "scenes" / "car.toml").write_text(car)
    for command in (["run", "{root}/scenes/car.toml", "--no-plots", "--out", "{out}"],
                    ["tune", "{root}/scenes/car.toml", "--workers", "0", "--out", "{out}"]):
        out["vehicle"].append(Base("vehicle", "scenes/drive.csv", (root / "scenes" / "drive.csv").read_text(), command))
        out["cueing"].append(Base("cueing", "scenes/car.toml", car, command))
    for command in (["run", "{root}/scenes/meng_eq35.toml", "--duration", "0.3", "--out", "{disk}/out"],
                    ["run", "{root}/scenes/meng_eq35.toml", "--duration", "1.0", "--no-plots", "--out", "{disk}/out"],
                    ["run", "{root}/meng.ssp", "--duration", "0.5", "--out", "{disk}/out"],
                    ["export", "{root}/scenes/meng_eq35.toml", "--ssp", "{disk}/out/meng.ssp", "--scene-step"],
                    ["sweep", "{root}/sweeps/brief.toml", "--workers", "0", "--out", "{disk}/out"],
                    ["design", "{root}/studies/tiny.toml", "--out", "{disk}/out"]):
        out["disk"].append(Base("disk", None, "", command))
    out["cache"].append(Base("cache", None, "", ["sweep", "{root}/sweeps/brief.toml", "--workers", "1", "--out",
                                                 "{out}"]))
    return out


class _quiet:
    def __enter__(self):
        self.saved = sys.stdout, sys.stderr
        sys.stdout = sys.stderr = io.StringIO()

    def __exit__(self, *exc):
        sys.stdout, sys.stderr = self.saved


VALUES = {  # form -> (where a value stands, the hostile values, how one is written there)
    "toml": (r'=\s*("[^"\n]*"|\[[^\]\n]*\]|\{[^}\n]*\}|[^\s,}\]#\n]+)', HOSTILE, "= {}"),
    "xml": (r'="([^"]*)"', HOSTILE_XML, '="{}"'),
    "csv": (r"[-+0-9.eE]+|[a-z]+", ["nan", "inf", "-1", "1e300", "", "x", "1,2", "0", "-0.0", "time"], "{}"),
}


def mutate(text: str, rng: random.Random, form: str) -> tuple[str, str]:
    """One mutation of `text` (a TOML, XML or CSV file) and what it was."""
    lines = text.split("\n")
    kind = rng.choice(["value", "value", "value", "delete", "duplicate", "swap", "misspell", "cut"])
    if kind == "value":
        pattern, hostile, written = VALUES[form]
        spots = list(re.finditer(pattern, text))
        if spots:
            spot = rng.choice(spots)
            new = rng.choice(hostile)
            return (text[:spot.start()] + written.format(new) + text[spot.end():],
                    f"value at {spot.start()} -> {new!r}")
        kind = "delete"
    if kind == "misspell":
        names = list(re.finditer(r'[A-Za-z_][A-Za-z_.\[\]0-9]{2,}', text))
        name = rng.choice(names)
        word = name.group(0)
        k = rng.randrange(len(word) - 1)
        wrong = word[:k] + word[k + 1] + word[k] + word[k + 2:] if rng.random() < 0.5 else word[:k] + word[k + 1:]
        return text[:name.start()] + wrong + text[name.end():], f"{word!r} -> {wrong!r}"
    if kind == "cut":
        at = rng.randrange(len(text))
        return text[:at], f"cut at {at} of {len(text)}"
    i = rng.randrange(len(lines))
    if kind == "delete":
        return "\n".join(lines[:i] + lines[i + 1:]), f"line {i + 1} deleted"
    if kind == "duplicate":
        return "\n".join(lines[:i + 1] + lines[i:]), f"line {i + 1} duplicated"
    j = rng.randrange(len(lines))
    lines[i], lines[j] = lines[j], lines[i]
    return "\n".join(lines), f"lines {i + 1} and {j + 1} swapped"


def mutate_bytes(data: str, rng: random.Random) -> tuple[str, str]:
    """One mutation of an archive's bytes (held as latin-1 text)."""
    kind = rng.choice(["byte", "byte", "cut out", "cut short"])
    at = rng.randrange(len(data))
    if kind == "byte":
        new = chr(rng.randrange(256))
        return data[:at] + new + data[at + 1:], f"byte {at} -> {ord(new)}"
    if kind == "cut out":
        length = rng.randrange(1, 4096)
        return data[:at] + data[at + length:], f"{length} bytes cut out at {at}"
    return data[:at], f"cut at {at} of {len(data)}"


ESCAPED = "cosim-fuzz-escaped"  # what an archive entry that climbs out of its folder would write


def mutate_archive(data: str, rng: random.Random) -> tuple[str, str]:
    """The archive (latin-1 text of its bytes) with one hostile entry added or an entry spoiled."""
    kind = rng.choice(["bomb", "climb", "link", "entries", "big", "garbage fmu", "no ssd", "twice"])
    import warnings
    source = zipfile.ZipFile(io.BytesIO(data.encode("latin-1")))
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a name twice is one of the mutations
        for info in source.infolist():
            content = source.read(info)
            if kind == "garbage fmu" and info.filename.endswith(".fmu") and rng.random() < 0.5:
                content = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 5000)))
            if kind == "no ssd" and info.filename == "SystemStructure.ssd":
                info = zipfile.ZipInfo("SystemStructure.xml")
            archive.writestr(info, content)
        if kind == "bomb":
            archive.writestr(f"resources/{rng.choice(['zeros', 'mechanics.fmu', 'x/y.bin'])}",
                             bytes(rng.choice([2, 20, 60]) << 20))
        elif kind == "climb":
            name = rng.choice([f"../{ESCAPED}", f"../../{ESCAPED}", f"/tmp/{ESCAPED}", f"resources/../../{ESCAPED}",
                               f"..\\{ESCAPED}", f"C:/{ESCAPED}"])
            archive.writestr(zipfile.ZipInfo(name), b"escaped")
        elif kind == "link":
            link = zipfile.ZipInfo(rng.choice(["resources/link", "SystemStructure.ssd.link"]))
            link.external_attr = 0o120777 << 16
            archive.writestr(link, rng.choice(["/etc/passwd", "../..", f"/tmp/{ESCAPED}"]))
        elif kind == "entries":
            for k in range(rng.choice([100, 11000])):
                archive.writestr(f"resources/many/{k}", b"")
        elif kind == "big":
            archive.writestr("resources/noise.bin", rng.randbytes(rng.choice([1, 3]) << 20))
        elif kind == "twice":
            archive.writestr("SystemStructure.ssd", source.read("SystemStructure.ssd")[::-1])
    return out.getvalue().decode("latin-1"), kind


def disk_setup(rng: random.Random) -> tuple[tuple, str]:
    """How full the small disk is before the command: the bytes left free."""
    leave = rng.choice([0, 1_000, 30_000, 200_000, 600_000, 1_500_000, 2_500_000])
    return ("fill", leave), f"{leave} bytes left free"


def cache_setup(rng: random.Random) -> tuple[tuple, str]:
    """What the sweep's cache holds before it runs: a planted file, or a cache not its own."""
    kind = rng.choice(["plant blob", "plant bundle", "plant both", "plant link", "shared", "not a folder", "linked",
                       "owner"])
    return (kind,), kind


def mutant(bases_of_kind: list[Base], seed: int, index: int) -> tuple[Base, str, str, tuple | None]:
    rng = random.Random(f"{seed}:{index}")
    base = bases_of_kind[index % len(bases_of_kind)]
    setup = None
    if base.kind == "ssp":
        text, what = mutate_bytes(base.text, rng)
    elif base.kind == "archive":
        text, what = mutate_archive(base.text, rng)
    elif base.kind in ("disk", "cache"):
        setup, what = (disk_setup if base.kind == "disk" else cache_setup)(rng)
        text, what = base.text, f"{' '.join(base.command[:2])}: {what}"
    else:
        text, what = mutate(base.text, rng, {"ssd": "xml", "ssv": "xml", "table": "csv", "vehicle": "csv"}.get(base.kind,
                                                                                                         "toml"))
    return base, text, what, setup


def prepare(setup: tuple | None, root: Path) -> None:
    """In the child, before the command: the disk filled, the cache planted or spoiled."""
    if setup is None:
        return
    kind = setup[0]
    if kind == "fill":
        (root / "disk" / "filler").write_bytes(bytes(max(0, shutil.disk_usage(root / "disk").free - setup[1])))
        return
    from cosim.engine.sweep.bundle import Bundle
    cache = root / "cache"
    clear(cache)  # (every run with an output folder keeps its lock there)
    bundle, _ = Bundle.of(root / "scenes" / "meng_eq35.toml")
    planted = {"plant blob": [cache / "blobs" / bundle.files[0][1]],
               "plant bundle": [cache / "bundles" / bundle.key / bundle.main]}
    planted["plant both"] = planted["plant blob"] + planted["plant bundle"]
    if kind in planted:
        for place in planted[kind]:
            place.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
            place.write_text((root / "scenes" / "meng_eq35.toml").read_text().replace("amplitude = 0.3",
                                                                                      "amplitude = 0.05"))
    elif kind == "plant link":
        place = cache / "bundles" / bundle.key / bundle.main
        place.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        place.symlink_to(root / "scenes" / "sumnu_case_1.toml")
    elif kind == "shared":
        cache.mkdir(exist_ok=True)
        cache.chmod(0o777)
    elif kind == "not a folder":
        cache.write_text("a file")
    elif kind == "linked":
        (root / "elsewhere").mkdir(exist_ok=True, mode=0o700)
        cache.symlink_to(root / "elsewhere")
    elif kind == "owner" and os.geteuid() == 0:
        cache.mkdir(exist_ok=True, mode=0o700)
        os.chown(cache, 65534, 65534)


def aftermath(base: Base, code: int | None, root: Path, reference: list[dict] | None) -> str | None:
    """What a hostile place's run left that breaks the rules, or None; and the place restored."""
    problem = None
    if base.kind in BINARY:
        left = [p.name for p in (root / "tmp").glob("cosim-ssp-*")]
        escaped = [str(p) for p in (root.parent / ESCAPED, root.parent.parent / ESCAPED, Path("/tmp") / ESCAPED,
                                    root / "out" / ESCAPED) if p.exists()]
        problem = (f"left its unpacked copy: {left}" if left else None) or \
            (f"an entry landed outside: {escaped}" if escaped else None)
    elif base.kind == "disk":
        problem = half_written(root / "disk")
        for item in (root / "disk").iterdir():
            shutil.rmtree(item) if item.is_dir() else item.unlink()
    elif base.kind == "cache":
        if code == 0 and reference is not None:
            import pyarrow.parquet as pq
            rows = pq.read_table(root / "out" / "brief.parquet").to_pylist()
            if comparable(rows) != comparable(reference):
                problem = "the rows are not the sweep's own: a planted file ran"
        clear(root / "cache")
    return problem


def clear(path: Path) -> None:
    """Whatever stands at `path` (a folder, a file, a link) removed."""
    if path.is_symlink() or path.is_file():
        path.unlink()
    elif path.exists():
        path.chmod(0o700)
        shutil.rmtree(path)


def comparable(rows: list[dict]) -> list[dict]:
    return [{k: v for k, v in row.items() if k not in ("wall", "real_time_factor")} for row in rows]


def half_written(folder: Path) -> str | None:
    """A file under a final name that is not whole, or a temporary file left, in `folder`."""
    for path in folder.rglob("*"):
        if path.name.endswith(".part"):
            return f"a temporary file left: {path.name}"
        if path.suffix == ".csv" and path.stat().st_size:
            import csv
            with open(path, newline="", errors="replace") as f:
                widths = {len(row) for row in csv.reader(f)}
            if not path.read_bytes().endswith(b"\n") or len(widths) > 1:
                return f"{path.name} is cut short"
        if path.suffix == ".png" and not path.read_bytes().endswith(b"IEND\xaeB`\x82"):
            return f"{path.name} is cut short"
        if path.suffix == ".html" and not path.read_text(errors="replace").rstrip().endswith("</html>"):
            return f"{path.name} is cut short"
        if path.suffix in (".ssp", ".parquet") and path.name != "filler":
            try:
                if path.suffix == ".ssp":
                    zipfile.ZipFile(path).testzip()
                else:
                    import pyarrow.parquet as pq
                    pq.read_table(path)
            except Exception as error:  # noqa: BLE001 - any reader's refusal is the finding
                return f"{path.name} is not whole ({error})"
    return None


def run_child(base: Base, text: str, root: Path, log: Path, setup: tuple | None = None) -> int:
    """Forks a child that writes the mutant into the work tree `root` (or prepares the place a
    command reads from or writes to) and runs the CLI on it (output in root/out, emptied first;
    temporary files in root/tmp, the sweep cache in root/cache); returns its pid."""
    pid = os.fork()
    if pid:
        return pid
    code = 4
    try:
        fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        sys.stdout = os.fdopen(1, "w", buffering=1)
        sys.stderr = os.fdopen(2, "w", buffering=1)
        shutil.rmtree(root / "out", ignore_errors=True)
        (root / "tmp").mkdir(exist_ok=True)
        os.environ.update(TMPDIR=str(root / "tmp"), COSIM_CACHE_DIR=str(root / "cache"))
        tempfile.tempdir = None
        prepare(setup, root)
        if base.name is not None:
            (root / base.name).write_bytes(text.encode("latin-1") if base.kind in BINARY else text.encode())
        code = main([a.replace("{root}", str(root)).replace("{out}", str(root / "out")).replace("{disk}", str(root / "disk"))
                     for a in base.command])
    except SystemExit as done:
        code = done.code if isinstance(done.code, int) else 2
    except BaseException:  # noqa: BLE001 - what main did not catch is the finding
        import traceback
        traceback.print_exc()
        code = 5
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code if isinstance(code, int) else 4)


def verdict(code: int | None, output: str) -> str | None:
    """Why a mutant's end breaks the rules, or None."""
    if code is None:
        return f"no end within {TIME_LIMIT:g} s (a hang)"
    if "Traceback" in output or code not in (0, 1, 2):
        return f"exit {code}" + (" with a traceback" if "Traceback" in output else "")
    if "RuntimeWarning" in output:
        return "a numpy warning leaked"
    errors = [line for line in output.splitlines() if line.startswith("error:")]
    if code == 2 and len(errors) != 1:
        return f"exit 2 with {len(errors)} error lines"
    if code == 2 and any(not line.strip() for line in errors):
        return "exit 2 with an empty error"
    return None


def fuzz(kinds: dict[str, list[Base]], seed: int, count: int, pristine: Path, parallel: int = 2) -> list[str]:
    """Runs `count` mutants of each kind, `parallel` at a time, each slot in its own copy of the
    work tree; returns the violations, each with its replay line."""
    violations, running = [], {}
    todo = [(kind, index) for kind in kinds for index in range(count)]
    tally = {kind: {0: 0, 1: 0, 2: 0} for kind in kinds}
    start = time.time()
    slots = [pristine.parent / f"slot{k}" for k in range(parallel)]
    for slot in slots:
        if not (slot / "scenes").exists():  # (the slot may hold its small disk already)
            shutil.copytree(pristine, slot, dirs_exist_ok=True)
    free = list(range(parallel))
    while todo or running:
        while todo and free:
            kind, index = todo.pop(0)
            slot = free.pop()
            base, text, what, setup = mutant(kinds[kind], seed, index)
            log = slots[slot] / "log.txt"
            pid = run_child(base, text, slots[slot], log, setup)
            running[pid] = (kind, index, what, slot, log, time.time(), base)
        time.sleep(0.002)
        for pid, (kind, index, what, slot, log, began, base) in list(running.items()):
            done, status = os.waitpid(pid, os.WNOHANG)
            if not done and time.time() - began < TIME_LIMIT:
                continue
            if not done:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
                code = None
            else:
                code = os.waitstatus_to_exitcode(status)
            output = log.read_text(errors="replace")
            # the next mutant starts from the original
            if base.name is not None:
                (slots[slot] / base.name).write_bytes(base.text.encode("latin-1") if base.kind in BINARY else
                                                      base.text.encode())
            problem = verdict(code, output) or aftermath(base, code, slots[slot], REFERENCE.get(kind))
            if problem:
                last = output.strip().splitlines()[-3:] if output.strip() else []
                violations.append(f"{kind} seed {seed} mutant {index} ({what}): {problem}: {' | '.join(last)}\n"
                                  f"  replay: .venv/bin/python tests/fuzz/fuzz_inputs.py --replay {kind} {seed} {index}")
            elif code in (0, 1, 2):
                tally[kind][code] += 1
            del running[pid]
            free.append(slot)
    for kind, counts in tally.items():
        print(f"inputs: {kind}: seed {seed}, {count} mutants: {counts[0]} ran, {counts[1]} failed runs with their "
              f"report, {counts[2]} one-line errors, {sum(v.startswith(kind + ' ') for v in violations)} violations",
              flush=True)
    print(f"inputs: seed {seed} done in {time.time() - start:.0f} s", flush=True)
    return violations


def replay(kinds: dict[str, list[Base]], kind: str, seed: int, index: int, root: Path) -> int:
    base, text, what, setup = mutant(kinds[kind], seed, index)
    print(f"{kind} seed {seed} mutant {index}: {what}")
    if kind not in (*BINARY, "disk", "cache"):
        sys.stdout.writelines(difflib.unified_diff(base.text.splitlines(True), text.splitlines(True), "original",
                                                   "mutant"))
    log = root.parent / "replay.txt"
    pid = run_child(base, text, root, log, setup)
    _, status = os.waitpid(pid, 0)
    code = os.waitstatus_to_exitcode(status)
    print(f"--- exit {code}; it printed:\n{log.read_text(errors='replace')}")
    problem = verdict(code, log.read_text(errors="replace")) or aftermath(base, code, root, REFERENCE.get(kind))
    print(f"verdict: {problem or 'within the rules'}")
    return 1 if problem else 0


REFERENCE: dict[str, list[dict]] = {}  # per kind, the rows its runs must give (the cache kind's sweep)


def reference_rows(work: Path) -> list[dict]:
    """The cache kind's sweep run in this process: the rows a run from any cache must give."""
    from cosim.engine.sweep import run_sweep
    from cosim.platform.run.sweep import load_sweep
    sweep = load_sweep(work / "sweeps" / "brief.toml")
    with _quiet():
        return run_sweep(sweep.name, sweep.points, sweep.evaluate, sweep.columns, work.parent / "reference",
                         sweep.signature, workers=0, progress=False).rows


@contextmanager
def small_disks(folder: Path, parallel: int = 2):
    """A tmpfs of 3 MB at slot<k>/disk for each slot (the disk kind's place); yields whether they
    could be mounted (root only), and unmounts them afterwards."""
    import subprocess
    disks = [folder / f"slot{k}" / "disk" for k in range(parallel)] + [folder / "pristine" / "disk"]
    mounted = []
    for disk in disks:
        disk.mkdir(parents=True, exist_ok=True)
        if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=3m", "tmpfs", str(disk)], capture_output=True).returncode:
            break
        mounted.append(disk)
    try:
        yield len(mounted) == len(disks)
    finally:
        for disk in mounted:
            subprocess.run(["umount", str(disk)], capture_output=True)


def arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mutants", type=int, default=40, help="mutants per file kind and seed (CI)")
    parser.add_argument("--long", action="store_true", help="10 000 mutants per file kind, seed 1 (every command "
                        "that reads a kind takes its share)")
    parser.add_argument("--seed", type=int, help="one seed instead of 1 and a new one")
    parser.add_argument("--kinds", default="scene,sweep,ssd,ssv,table,ssp,archive,disk,cache,study,vehicle,cueing")
    parser.add_argument("--replay", nargs=3, metavar=("KIND", "SEED", "INDEX"))
    return parser.parse_args()


if __name__ == "__main__":
    args = arguments()
    with tempfile.TemporaryDirectory(prefix="fuzz_inputs_") as folder, small_disks(Path(folder)) as mounted:
        work = Path(folder) / "pristine"
        kinds = {k: v for k, v in bases(work).items() if k in args.kinds.split(",")}
        if "disk" in kinds and not mounted:
            print("inputs: disk: not run (a tmpfs cannot be mounted here: it needs root)", flush=True)
            del kinds["disk"]
        if "cache" in kinds:
            REFERENCE["cache"] = reference_rows(work)
        if args.replay:
            sys.exit(replay(kinds, args.replay[0], int(args.replay[1]), int(args.replay[2]), work))
        seeds = [1] if args.long else ([args.seed] if args.seed is not None else [1, int(time.time()) % 1000000007])
        count = 10000 if args.long else args.mutants
        print(f"inputs: seeds {', '.join(map(str, seeds))}, {count} mutants per file kind and seed "
              f"(replay: .venv/bin/python tests/fuzz/fuzz_inputs.py --replay KIND SEED INDEX)", flush=True)
        found = [v for seed in seeds for v in fuzz(kinds, seed, count, work)]
        for line in found:
            print(line)
        print(f"inputs: {len(found)} violations (tracebacks, hangs, exits other than 0/1/2, multi-line errors)")
        sys.exit(1 if found else 0)
