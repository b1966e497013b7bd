#!/usr/bin/env bash
# The FMUs under hostile use: builds the fuzz harnesses (FMI 2.0, Co-Simulation and Model Exchange,
# and, through the FMI 3.0 layer, FMI 3.0) and the thread test of every FMU (tests/fuzz/) under
# AddressSanitizer + UBSan and ThreadSanitizer in build-fuzz/, then runs them.
#   bash scripts/fuzz.sh          CI: seeds 1 and 2 (2 x 1000 sequences per FMU) and one new seed
#                                 (1000 more, printed so a failure can be replayed)
#   bash scripts/fuzz.sh long     100 000 sequences per FMU (seed 1)
#   bash scripts/fuzz.sh replay MODEL SEED INDEX    one sequence, every call printed (replay3: FMI 3.0)
#   bash scripts/fuzz.sh replay-system FMU SEED INDEX   one sequence against a system FMU (FMU: one of
#                                 SYSTEM_FMUS, exported into build-fuzz/system_fmus/ by the last run)
#   bash scripts/fuzz.sh long-inputs              10 000 mutants of each input file kind (seed 1)
# CI also fuzzes the files a user writes (tests/fuzz/fuzz_inputs.py): seeded mutations of every
# shipped scene and sweep file, of an exported SSD, SSV and archive (hostile entries too), of a
# vehicle's motion and its cueing scene, each run briefly through every command that reads it, and
# the places they go: a disk filled before a run, export, sweep or
# design writes to it (a tmpfs: root), a sweep cache with planted files or the wrong owner or mode;
# any traceback, hang, exit other than 0/1/2, multi-line error, unpacked copy left behind,
# half-written file or planted file run fails it.
# The whole system as one FMU is fuzzed too (the same harnesses built for a system FMU: fuzz_system
# its FMI 2.0 layer, fuzz3_system its FMI 3.0 layer, under the sanitizers, the nested FMUs as the
# export ships them): Meng's scene and the MPC car drive, each exported as Co-Simulation and as Model Exchange, in
# FMI 2.0 and in FMI 3.0.
# Each run also checks for leaks (LeakSanitizer: every sequence instantiates and frees an instance)
# and steps six instances on six threads against a sequential run (ThreadSanitizer reports races).
# Exits non-zero on any violation, sanitizer report or difference.
set -euo pipefail
cd "$(dirname "$0")/.."
MODELS=$(grep -E '^[a-z0-9_]+$' fmu/models.txt)  # the shipped models, one list
CMAKE=.venv/bin/cmake
[ -x "$CMAKE" ] || CMAKE=cmake
"$CMAKE" -S . -B build-fuzz -DCOSIM_FUZZ=ON -DCOSIM_SANITIZE=ON -DPython3_EXECUTABLE="$PWD/.venv/bin/python" \
  > build-fuzz.log 2>&1 || { cat build-fuzz.log; exit 1; }
targets="fuzz_system fuzz3_system"
for m in $MODELS; do targets="$targets fuzz_$m fuzz3_$m threads_$m"; done
# shellcheck disable=SC2086
"$CMAKE" --build build-fuzz -j 2 --target $targets >> build-fuzz.log 2>&1 || { cat build-fuzz.log; exit 1; }
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export TSAN_OPTIONS=halt_on_error=1
mode=${1:-ci}
# the system FMUs: SCENE_INTERFACE[3] (3: FMI 3.0, fuzzed by fuzz3_system; else FMI 2.0, fuzz_system)
SYSTEM_FMUS="meng_cs meng_me car_cs car_me meng_cs3 meng_me3 car_cs3 car_me3"
harness() { case "$1" in *3) echo build-fuzz/fuzz3_system ;; *) echo build-fuzz/fuzz_system ;; esac; }
export_systems() {  # the system FMUs the harnesses run on, exported as a user does and unpacked
  local folder=build-fuzz/system_fmus scene options
  rm -rf "$folder" && mkdir -p "$folder"
  for name in $SYSTEM_FMUS; do
    case "$name" in meng_*) scene=scenes/meng_eq35.toml ;; *) scene=examples/vehicle/car_drive_mpc.toml ;; esac
    options=""
    case "$name" in *_me*) options="--me" ;; esac
    case "$name" in *3) options="$options --fmi 3" ;; esac
    # shellcheck disable=SC2086
    .venv/bin/python -m cosim export "$scene" --fmu "$folder/$name.fmu" --duration 2 $options \
      > "$folder/$name.log" 2>&1 || { cat "$folder/$name.log"; exit 1; }
    .venv/bin/python -c "import sys, zipfile; zipfile.ZipFile(sys.argv[1]).extractall(sys.argv[2])" \
      "$folder/$name.fmu" "$folder/$name"
  done
}
start=$(date +%s)
case "$mode" in
  long-inputs)
    exec .venv/bin/python tests/fuzz/fuzz_inputs.py --long ;;
  replay)
    exec "build-fuzz/fuzz_$2" --seed "$3" --replay "$4" --verbose ;;
  replay3)
    exec "build-fuzz/fuzz3_$2" --seed "$3" --replay "$4" --verbose ;;
  replay-system)
    exec "$(harness "$2")" --fmu-dir "$PWD/build-fuzz/system_fmus/$2" --seed "$3" --replay "$4" --verbose ;;
  long)
    for m in $MODELS; do
      "build-fuzz/fuzz_$m" --seed 1 --sequences 100000
      "build-fuzz/fuzz3_$m" --seed 1 --sequences 100000
    done
    export_systems
    for name in $SYSTEM_FMUS; do
      "$(harness "$name")" --fmu-dir "$PWD/build-fuzz/system_fmus/$name" --seed 1 --sequences 10000
    done ;;
  ci)
    new_seed=$(( $(date +%s) % 1000000007 ))
    echo "fuzz: fixed seeds 1 and 2, new seed $new_seed (replay: bash scripts/fuzz.sh replay|replay3 MODEL SEED INDEX)"
    for m in $MODELS; do
      for seed in 1 2 "$new_seed"; do
        "build-fuzz/fuzz_$m" --seed "$seed" --sequences 1000
        "build-fuzz/fuzz3_$m" --seed "$seed" --sequences 1000
      done
      "build-fuzz/threads_$m"
    done
    export_systems
    for name in $SYSTEM_FMUS; do
      for seed in 1 "$new_seed"; do
        "$(harness "$name")" --fmu-dir "$PWD/build-fuzz/system_fmus/$name" --seed "$seed" --sequences 1000
      done
    done
    # a new seed's find kept: a step of 160 s on Meng's system with every log category on (about a
    # minute's bounded work, within the system harness's HANG_SECONDS, tests/fuzz/fuzz_common.h)
    "$(harness meng_cs)" --fmu-dir "$PWD/build-fuzz/system_fmus/meng_cs" --seed 796624656 --replay 931
    .venv/bin/python tests/fuzz/fuzz_inputs.py --mutants 40 ;;
  *) echo "usage: bash scripts/fuzz.sh [ci | long | long-inputs | replay MODEL SEED INDEX | replay3 MODEL SEED INDEX |" \
          "replay-system FMU SEED INDEX]" >&2
     exit 2 ;;
esac
echo "fuzz: done in $(( $(date +%s) - start )) s, no violations, sanitizer reports or differences"
