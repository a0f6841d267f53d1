#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the libFuzzer targets of tests/fuzz/ (fuzz_json: the atmosphere and scene JSON
# readers; fuzz_vdb: the VDB reader; fuzz_exr: the OpenEXR reader, image and depth inputs)
# with Debian's clang (-fsanitize=fuzzer,address) and
# runs each for a bounded time from its seed corpus in tests/fuzz/corpus/<target>/.
# Fails on any crash, sanitizer report, uncaught exception, leak, timeout or memory blow-up.
#
# The sources that read the input (src/io, src/atmosphere/json.cpp, src/scene/json.cpp,
# src/clouds/vdb.cpp, src/io/exr.cpp) are compiled instrumented; the rest of the core comes from the
# static libraries of the normal build (scripts/build.sh, in build/ unless BUILD_DIR).
#
#   scripts/fuzz.sh                 # 30 s per target (FUZZ_SECONDS), rss limit 3072 MB
#   FUZZ_SECONDS=300 scripts/fuzz.sh fuzz_vdb
# Findings (crash-*, leak-*, timeout-*, oom-*) are kept in build/fuzz/artifacts/.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

BUILD_DIR=${BUILD_DIR:-build}
SECONDS_PER_TARGET=${FUZZ_SECONDS:-30}
CXX_FUZZ=${CXX_FUZZ:-clang++}
targets=("$@")
((${#targets[@]})) || targets=(fuzz_json fuzz_vdb fuzz_exr)

if ! command -v "$CXX_FUZZ" >/dev/null; then
  echo "fuzz: $CXX_FUZZ not found (apt-get install clang libclang-rt-14-dev)" >&2
  exit 1
fi
# The core's layers, as the build declared them (cmake/WelkinLayers.cmake writes the list):
# a layer comes after those it builds on, so the link line takes them in reverse.
layers_file=$BUILD_DIR/welkin_layers.txt
[[ -f $layers_file ]] || { echo "fuzz: $layers_file missing: run scripts/build.sh" >&2; exit 1; }
mapfile -t layers <"$layers_file"
for lib in "${layers[@]}"; do
  [[ -f $BUILD_DIR/libwelkin_$lib.a ]] || { echo "fuzz: $BUILD_DIR/libwelkin_$lib.a missing: run scripts/build.sh" >&2; exit 1; }
done

out=$BUILD_DIR/fuzz
mkdir -p "$out/artifacts"
# The targets' scratch files (fuzz_vdb's and fuzz_exr's input files) go into a folder removed at the end.
scratch=$(mktemp -d "${TMPDIR:-/tmp}/welkin_fuzz.XXXXXX")
trap 'rm -rf "$scratch"' EXIT
export TMPDIR=$scratch
instrumented=(src/io/file.cpp src/io/json.cpp src/io/exr.cpp src/atmosphere/json.cpp src/scene/json.cpp
              src/clouds/vdb.cpp)
launcher=()
command -v ccache >/dev/null && launcher=(ccache)
libs=()
for ((i = ${#layers[@]} - 1; i >= 0; i--)); do libs+=("$BUILD_DIR/libwelkin_${layers[i]}.a"); done
libs+=(-lopenvdb -lboost_iostreams -lfmt -ltbb -lOpenEXR-3_1 -lImath-3_1 -lIlmThread-3_1 -lIex-3_1 -lerfa -lz -lm)

# Every target runs under AddressSanitizer. fuzz_vdb and fuzz_exr replace operator new (see
# the files): OpenVDB sizes buffers from lengths inside a grid's tree, OpenEXR from a
# header's data window, and ASan's own operator new would abort on such a request where the
# program gets std::bad_alloc (OutOfMemory).
sanitizers() { echo fuzzer,address; }

failed=()
# One line per failed target: what ended it and where its input went (scripts/test.sh prints
# this file last, so that the reason is in the tail of a long CI log).
findings=$out/findings.txt
: >"$findings"
for t in "${targets[@]}"; do
  san=$(sanitizers "$t")
  obj=$out/obj_${san//,/_}
  mkdir -p "$obj"
  flags=(-std=c++20 -O1 -g -fno-omit-frame-pointer "-fsanitize=${san/fuzzer/fuzzer-no-link}"
         -Iinclude -I/usr/include/OpenEXR -I/usr/include/Imath -DNDEBUG)
  objs=()
  for src in "${instrumented[@]}" "tests/fuzz/$t.cpp"; do
    o=$obj/$(echo "$src" | tr / _).o
    "${launcher[@]}" "$CXX_FUZZ" "${flags[@]}" -c "$src" -o "$o"
    objs+=("$o")
  done
  "$CXX_FUZZ" "-fsanitize=$san" "${objs[@]}" "${libs[@]}" -o "$out/$t"
  corpus=tests/fuzz/corpus/${t#fuzz_}
  work=$out/corpus_${t#fuzz_}   # new inputs found go here; the repository's corpus stays as it is
  mkdir -p "$work"
  echo "--- $t (-fsanitize=$san): $SECONDS_PER_TARGET s from $corpus"
  # detect_leaks=0: OpenVDB and TBB keep process-wide singletons alive on purpose.
  # timeout: a crash that corrupts the heap can deadlock libFuzzer's own crash handler;
  # that must fail the run, not hang it. -seed: the same run every time (FUZZ_SEED).
  if ! ASAN_OPTIONS=detect_leaks=0:abort_on_error=1:alloc_dealloc_mismatch=0:quarantine_size_mb=64 timeout -k 5 $((SECONDS_PER_TARGET + 60)) \
      "$out/$t" "$work" "$corpus" -seed="${FUZZ_SEED:-1}" \
      -max_total_time="$SECONDS_PER_TARGET" -rss_limit_mb=3072 -malloc_limit_mb=2048 -timeout=10 \
      -max_len=65536 -artifact_prefix="$out/artifacts/$t-" -print_final_stats=1 \
      >"$out/$t.log" 2>&1; then
    tail -n 40 "$out/$t.log" >&2
    failed+=("$t")
    # The first report of the fuzzer's own process (a sanitizer's or an uncaught exception,
    # before libFuzzer's "deadly signal" that follows it; fuzz_vdb's reader children report
    # the corrupt trees they die of, by design, so a target that forks names its process),
    # the first frames of its stack, and the last lines (which input, where it went).
    host=$(sed -n 's/^.*: host process \([0-9]*\)$/\1/p' "$out/$t.log" | head -n 1)
    reason=$(awk -v host="${host:+==$host==}" '
                  !first && (/terminate called/ || (/ERROR: |ALARM: |out-of-memory/ && index($0, host))) {
                      first = 1; print; next }
                  first == 1 && /what\(\):/ { print }
                  first && /^ *#[0-9]+ / && !/fuzzer::|__sanitizer|libc\.so|libstdc|raise|abort|pthread_kill/ &&
                  frames++ < 6 { sub(/^ */, ""); sub(/0x[0-9a-f]+ in /, ""); sub(/ \(BuildId: [0-9a-f]+\)/, ""); print }' "$out/$t.log"
             grep -E "SUMMARY: |Test unit written" "$out/$t.log" | tail -n 2)
    echo "$t: ${reason:-no report in $out/$t.log (killed by timeout?)}" | cut -c1-300 >>"$findings"
    # A small input goes into the findings whole (gzip, base64), so that a failure on a
    # machine whose files are gone can be reproduced from its log.
    unit=$(grep -oE "Test unit written to [^ ]+" "$out/$t.log" | tail -n 1 | cut -d' ' -f5)
    if [[ -n $unit && -f $unit ]]; then
      packed=$(gzip -9c "$unit" | base64 -w0)
      ((${#packed} <= 6000)) && echo "$t: input (gzip | base64): $packed" >>"$findings"
    fi
  else
    grep -E "^(stat::number_of_executed_units|Done)" "$out/$t.log" || tail -n 2 "$out/$t.log"
  fi
done
if ((${#failed[@]})); then
  echo "fuzz: FAILED: ${failed[*]} (inputs in $out/artifacts/)" >&2
  exit 1
fi
echo "fuzz: no findings"
