#!/usr/bin/env bash
# Time to first image: the wall time of `aerial render SCENE --out tmp.png`
# from process start to exit, for every scene given, with the driver's own
# shader cache (Mesa's) off or warm and aerial's pipeline cache off (not on
# disk), cold (an empty folder) or warm (filled by an earlier run).
# Prints one line per scene and case: the median of RUNS runs, then every
# run's time, in seconds.
#
#   scripts/time-to-first-image.sh [AERIAL] [RUNS] [WIDTH HEIGHT] -- SCENE...
#
# AERIAL defaults to ./target/release/aerial, RUNS to 3, the size to
# 160x90 (the compile is what is measured, not the frame). Every cache lives
# in a temporary folder removed at the end; the user's caches are not
# touched.
set -euo pipefail

aerial=./target/release/aerial
runs=3
width=160
height=90
positional=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do
  positional+=("$1")
  shift
done
[ "${1:-}" = "--" ] && shift
[ ${#positional[@]} -ge 1 ] && aerial=${positional[0]}
[ ${#positional[@]} -ge 2 ] && runs=${positional[1]}
[ ${#positional[@]} -ge 4 ] && width=${positional[2]} && height=${positional[3]}
if [ $# -eq 0 ]; then
  echo "usage: $0 [AERIAL] [RUNS] [WIDTH HEIGHT] -- SCENE..." >&2
  exit 2
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# One timed render (bash's own `time`, wall seconds); the caches are chosen
# by the environment given.
timed() {
  local TIMEFORMAT=%R
  { time env "$@" "$aerial" render "$scene" --width "$width" --height "$height" \
    --out "$work/out.png" >/dev/null 2>"$work/stderr"; } 2>&1 || {
    cat "$work/stderr" >&2
    exit 1
  }
}

median() {
  tr ' ' '\n' | sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'
}

cases=("off off" "off cold" "off warm" "warm off" "warm cold" "warm warm")
for scene in "$@"; do
  # Warm caches: filled by one untimed run each.
  rm -rf "$work/mesa-warm" "$work/ours-warm"
  env MESA_SHADER_CACHE_DIR="$work/mesa-warm" AERIAL_PIPELINE_CACHE="$work/ours-warm/" \
    "$aerial" render "$scene" --width "$width" --height "$height" --out "$work/out.png" \
    >/dev/null 2>&1
  declare -A times=()
  # Round by round, every case once per round, so that a change in the
  # machine's load falls on every case alike.
  for _ in $(seq "$runs"); do
    for case in "${cases[@]}"; do
      read -r mesa ours <<<"$case"
      rm -rf "$work/ours-cold"
      mesa_env=(MESA_SHADER_CACHE_DISABLE=true)
      [ "$mesa" = warm ] && mesa_env=(MESA_SHADER_CACHE_DIR="$work/mesa-warm")
      case $ours in
        off) ours_env=(AERIAL_PIPELINE_CACHE=off) ;;
        cold) ours_env=(AERIAL_PIPELINE_CACHE="$work/ours-cold/") ;;
        warm) ours_env=(AERIAL_PIPELINE_CACHE="$work/ours-warm/") ;;
      esac
      times[$case]+="$(timed "${mesa_env[@]}" "${ours_env[@]}") "
    done
  done
  for case in "${cases[@]}"; do
    read -r mesa ours <<<"$case"
    printf '%s mesa=%s ours=%s median=%s runs=%s\n' "$(basename "$scene")" "$mesa" "$ours" \
      "$(echo ${times[$case]} | median)" "${times[$case]% }"
  done
  unset times
  ls -l "$work/ours-warm" | awk 'NR > 1 { print "  pipeline cache file: " $5 " bytes" }'
done
