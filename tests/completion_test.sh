#!/usr/bin/env bash
# The bash completion that `kodawari completion bash` writes from the command's own option
# definitions: sourced in bash, it offers the subcommands, their options, the values of a
# choice and file names where a file goes.
# usage: completion_test.sh KODAWARI_BINARY SOURCE_DIR
set -uo pipefail
bin=$1
src=$2
source "$(dirname "${BASH_SOURCE[0]}")/check.sh"

"$bin" completion bash >"$work/kodawari.bash"
check "completion bash exits 0 and writes a script" test -s "$work/kodawari.bash"
check "the script is valid bash" bash -n "$work/kodawari.bash"
"$bin" completion zsh >/dev/null 2>"$work/zsh.err"
check "an unknown shell exits 2 naming it" bash -c "test $? -eq 2 && grep -q 'zsh' '$work/zsh.err'"

# complete WORD... : what _kodawari offers for the command line WORD... (the last word is
# the one under the cursor), one per line, sorted.
complete_words() {
    bash -c 'source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$((${#COMP_WORDS[@]} - 1)); _kodawari; printf "%s\n" "${COMPREPLY[@]}" | sort' \
        _ "$work/kodawari.bash" "$@"
}
offers() {  # offers "EXPECTED WORDS" WORD... : the offer is exactly EXPECTED
    local expected=$1; shift
    test "$(complete_words "$@" | tr '\n' ' ')" == "$(printf '%s\n' $expected | sort | tr '\n' ' ')"
}

check "the commands" bash -c "$(declare -f complete_words); work='$work'; complete_words kodawari '' | grep -qx bench && complete_words kodawari '' | grep -qx completion"
check "kodawari re -> render" offers "render" kodawari re
check "kodawari bench ch -> chains" offers "chains" kodawari bench ch
check "kodawari bench -> its six benchmarks" offers "birds ceilings chains crowd flock view" kodawari bench ''
check "bench chains --f -> --frames" offers "--frames" kodawari bench chains --f
check "bench chains --st -> the deprecated --steps still completes" offers "--steps" kodawari bench chains --st
check "run --ba -> --backend" offers "--backend" kodawari run --ba
check "run --fi -> --fit-routes (the route check)" offers "--fit-routes" kodawari run --fi
check "validate --str -> --strict" offers "--strict" kodawari validate --str
check "run --backend -> the backends" offers "auto cpu cpu-reference vulkan" kodawari run --backend ''
check "render --isa -> the instruction sets" offers "avx2 avx512 scalar sse4" kodawari render --isa ''
mkdir -p "$work/files/sub"
touch "$work/files/scene-a.json" "$work/files/scene-b.json"
check "run SCENE completes file names" offers "$work/files/scene-a.json $work/files/scene-b.json" kodawari run "$work/files/scene-"
check "run --out completes file names" offers "$work/files/scene-a.json $work/files/scene-b.json" kodawari run --out "$work/files/scene-"
check "render --out completes directories" offers "$work/files/sub" kodawari render --out "$work/files/s"
check "run --frames offers nothing (a number)" offers "" kodawari run --frames ''
check "the options of info" offers "--device" kodawari info --d
check "completion's shell" offers "bash" kodawari completion b
check "sketch --key -> motion pose" offers "motion pose" kodawari sketch --key ''
check "sketch --measure -> the three measures" offers "acceleration angular_speed speed" kodawari sketch --measure ''
check "sketch --sm -> --smoothing" offers "--smoothing" kodawari sketch --sm
check "rig --mo -> --motion --motion-map" offers "--motion --motion-map" kodawari rig --mo
check "rig --motion completes file names" offers "$work/files/scene-a.json $work/files/scene-b.json" kodawari rig --motion "$work/files/scene-"

echo "completion: $passed passed, $failed failed"
test $failed -eq 0
