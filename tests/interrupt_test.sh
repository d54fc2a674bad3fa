#!/usr/bin/env bash
# An interrupted bake leaves nothing behind (issue 16's first fault): SIGINT while a
# trace is being written, SIGTERM while the .glb is being assembled, and SIGINT to mpirun
# (which passes SIGTERM on to its ranks) while rank 0 writes; and two runs writing one
# output at once leave one whole run's file. Each interrupted run must end by that signal
# within seconds, and neither the output nor any `*.tmp-<pid>` file may remain, nor the
# unnamed file the output is written to before it is complete.
# usage: interrupt_test.sh KODAWARI_BINARY SOURCE_DIR WITH_MPI(0|1)
set -uo pipefail
# Job control: background jobs of a shell without it start with SIGINT ignored, and the
# command keeps a signal ignored (as nohup relies on).
set -m
bin=$1
src=$2
with_mpi=$3
source "$(dirname "${BASH_SOURCE[0]}")/check.sh"
scene="$src/scenes/murmuration.json"  # 12 000 birds x 600 frames: seconds of work here

# Waits (up to 60 s) until one of the processes matching pattern $1 has an output open in
# $work: an unnamed one (O_TMPFILE shows as "#<inode> (deleted)") or a named temporary
# file (`*.tmp-<pid>`, file systems without O_TMPFILE); returns 1 if none ever does.
writing() {
  local pid
  for pid in $(pgrep -f -- "$1"); do
    ls -l "/proc/$pid/fd" 2>/dev/null | grep -qE -- "$work/(#|m\..*\.tmp-)" && return 0
  done
  return 1
}
wait_for() {
  for _ in $(seq 1 3000); do
    writing "$1" && return 0
    sleep 0.02
  done
  return 1
}
# Sends signal $2 to pid $1, waits for it (at most 20 s) and sets $rc to its status.
stop() {
  kill -"$2" "$1"
  for _ in $(seq 1 200); do kill -0 "$1" 2>/dev/null || break; sleep 0.1; done
  wait "$1"
  rc=$?
}
nothing_left() { ! compgen -G "$work/m.*" >/dev/null; }
# Note: an output written unnamed (O_TMPFILE) disappears with the process whatever kills
# it; a named temporary file is removed by the signal handlers (AtomicFile).

"$bin" run "$scene" --backend cpu --out "$work/m.glb" --trace "$work/m.jsonl" >/dev/null 2>&1 &
pid=$!
check "the trace is being written" wait_for "[k]odawari run .*--trace $work/m.jsonl"
stop $pid INT
check "SIGINT while tracing ends the run by SIGINT (status 130)" test "$rc" -eq 130
check "SIGINT leaves neither output nor temporary file" nothing_left

"$bin" run "$scene" --backend cpu --out "$work/m.glb" >/dev/null 2>&1 &
pid=$!
check "the .glb is being written" wait_for "[k]odawari run .*--backend cpu --out $work/m.glb\$"
stop $pid TERM
check "SIGTERM while assembling the .glb ends the run by SIGTERM (status 143)" test "$rc" -eq 143
check "SIGTERM leaves neither output nor temporary file" nothing_left

# Two runs writing one output at once: the file is one whole run's, never a mix.
"$bin" run "$src/scenes/flock.json" --backend cpu --frames 100 --out "$work/a.glb" >/dev/null 2>&1
"$bin" run "$src/scenes/flock.json" --backend cpu --frames 200 --out "$work/b.glb" >/dev/null 2>&1
"$bin" run "$src/scenes/flock.json" --backend cpu --frames 100 --out "$work/same.glb" >/dev/null 2>&1 &
first=$!
"$bin" run "$src/scenes/flock.json" --backend cpu --frames 200 --out "$work/same.glb" >/dev/null 2>&1
wait $first
check "two runs on one output leave one whole run's file" bash -c "cmp -s '$work/same.glb' '$work/a.glb' || cmp -s '$work/same.glb' '$work/b.glb'"
check "two runs on one output leave no temporary file" bash -c "! ls '$work' | grep -q tmp"

if [[ "$with_mpi" == 1 ]]; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
  env ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" \
    mpirun --oversubscribe -np 2 "$bin" run "$scene" --backend cpu --threads 1 --mpi --out "$work/m.glb" >/dev/null 2>&1 &
  pid=$!
  check "rank 0 writes the .glb" wait_for "[k]odawari run .* --mpi --out $work/m.glb"
  stop $pid INT
  check "SIGINT to mpirun fails the run" test "$rc" -ne 0
  check "an interrupted MPI bake leaves neither output nor temporary file" nothing_left
  # ([k]: the pattern must not match this check's own command line.)
  check "no rank outlives mpirun" bash -c "! pgrep -f -- '[k]odawari run .* --mpi --out $work/m.glb' >/dev/null"
else
  echo "SKIP: the mpirun check: this kodawari was built without MPI"
fi

echo "passed $passed, failed $failed"
[[ $failed -eq 0 ]]
