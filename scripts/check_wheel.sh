#!/usr/bin/env bash
# The wheel as a new user gets it: built from this checkout (scikit-build-core, the C parts inside),
# installed into a fresh virtual environment outside the checkout, then, from a temporary folder
# and with no checkout in sight: `cosim --help`, the main scene by name, its SSP exported and run,
# and a sweep on a Dask scheduler and two workers started in yet another folder, whose rows must
# equal the same sweep run in one process. Exits non-zero on the first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
CHECKOUT=$PWD
PYTHON=${PYTHON:-python3}
WORK=$(mktemp -d)
PIDS=()
cleanup() {
  for pid in "${PIDS[@]}"; do kill "$pid" 2> /dev/null || true; done
  wait 2> /dev/null || true
  rm -rf "$WORK"
}
trap cleanup EXIT

echo "wheel: building"
.venv/bin/python -m pip wheel --quiet --no-deps --wheel-dir "$WORK/built" "$CHECKOUT" > "$WORK/wheel.log" 2>&1 \
  || { cat "$WORK/wheel.log"; exit 1; }
# a wheel the package index takes: auditwheel gives it the manylinux tag its binaries allow (they need
# libc and libm alone, nothing to vendor; tests/models/test_fmu_packages.py holds the FMUs to that)
PATH="$CHECKOUT/.venv/bin:$PATH" .venv/bin/auditwheel repair --wheel-dir "$WORK/wheel" "$WORK"/built/*.whl \
  >> "$WORK/wheel.log" 2>&1 || { cat "$WORK/wheel.log"; exit 1; }
WHEEL=$(ls "$WORK"/wheel/*.whl)
case "$WHEEL" in
  *-manylinux_*_x86_64.whl) echo "wheel: $(basename "$WHEEL")" ;;
  *) echo "the repaired wheel $(basename "$WHEEL") has no manylinux tag" >&2; exit 1 ;;
esac
"$PYTHON" -m venv "$WORK/venv"
# the wheel's own dependencies, at the versions the tests were run with
"$WORK/venv/bin/python" -m pip install --quiet "$WHEEL" -c requirements.txt
rm -rf "$WORK/venv/src" 2> /dev/null || true

mkdir -p "$WORK/user" "$WORK/cluster"
cd "$WORK/user"  # from here on, no path leads into the checkout
export PATH="$WORK/venv/bin:$PATH"
if "$WORK/venv/bin/python" -c "import cosim, sys; sys.exit('$CHECKOUT' in cosim.__file__)"; then :; else
  echo "the fresh environment imports cosim from the checkout" >&2; exit 1
fi
cosim --help > /dev/null
cosim run meng_eq35 --duration 0.5 --out out --no-plots
cosim export meng_eq35 --ssp meng.ssp
cosim run meng.ssp --duration 0.3 --out out_ssp
test -s out/meng_eq35.csv && test -s out_ssp/meng.csv

# a sweep of the shipped scene, copied out to edit, and of the SSP, on a scheduler and two workers
# started in another folder
cat > scene_sweep.toml <<EOF
[sweep]
scene = "meng_eq35"
duration = 0.2
[[axis]]
key = "scene.step"
values = [5e-4, 1e-3]
EOF
python - <<'EOF'
from cosim.platform.scene import load_scene
import shutil
shutil.copy(load_scene("meng_eq35").path, "my_scene.toml")
text = open("scene_sweep.toml").read().replace('scene = "meng_eq35"', 'scene = "my_scene.toml"')
open("scene_sweep.toml", "w").write(text)
open("ssp_sweep.toml", "w").write('[sweep]\nsystem = "meng.ssp"\nduration = 0.1\n[[axis]]\nkey = "step"\n'
                                  'values = [5e-4, 1e-3]\n')
EOF
(cd "$WORK/cluster" && COSIM_CACHE_DIR="$WORK/cluster/cache" exec dask scheduler --host 127.0.0.1 --port 0 \
   --no-dashboard --scheduler-file scheduler.json > scheduler.log 2>&1) &
PIDS+=($!)
for _ in $(seq 1 600); do [ -s "$WORK/cluster/scheduler.json" ] && break; sleep 0.1; done
ADDRESS=$(python -c "import json; print(json.load(open('$WORK/cluster/scheduler.json'))['address'])")
(cd "$WORK/cluster" && COSIM_CACHE_DIR="$WORK/cluster/cache" exec dask worker "$ADDRESS" --nworkers 2 \
   --nthreads 1 --no-dashboard --host 127.0.0.1 > workers.log 2>&1) &
PIDS+=($!)
python - "$ADDRESS" <<'EOF'
import sys
from distributed import Client
from cosim.engine.sweep import run_sweep
from cosim.platform.run.sweep import load_sweep
with Client(sys.argv[1], timeout="60s") as client:
    client.wait_for_workers(2, timeout=120)
for name in ("scene_sweep", "ssp_sweep"):
    sweep = load_sweep(f"{name}.toml")
    runs = [run_sweep(sweep.name, sweep.points, sweep.evaluate, sweep.columns, f"{name}_{where}", sweep.signature,
                      progress=False, **options).rows
            for where, options in (("here", {"workers": 0}), ("cluster", {"scheduler": sys.argv[1]}))]
    same = [[{k: v for k, v in row.items() if k not in ("wall", "real_time_factor")} for row in rows] for rows in runs]
    assert all(r["status"] == "ok" for r in runs[1]), [r["message"] for r in runs[1]]
    assert same[0] == same[1], f"{name}: the cluster's rows differ from this process's"
    print(f"wheel: {name} on two workers started elsewhere, {len(runs[1])} points bit for bit like one process")
EOF
test -n "$(ls "$WORK/cluster/cache/blobs")"
echo "wheel: OK (installed without the checkout: --help, a scene by name, its SSP, a cluster sweep)"
