#!/usr/bin/env bash
# Compare decophantom binaries on the issue-13 runs, alternated run by run (README "Speed",
# "How to measure"): this machine's speed drifts by up to 2x within minutes, so two codes
# compare only when their runs interleave.
#
# usage: benches/alternate.sh ROUNDS BINARY...
#   e.g. git worktree add /tmp/base REV && (cd /tmp/base && cargo build --release)
#        benches/alternate.sh 3 /tmp/base/target/release/decophantom target/release/decophantom
#
# For each run (the Fig. 5 dive, the oscillation, the small cube as fits run it, the demo's GF 30/85
# dive with its stops on two threads) and binary,
# prints the wall times of the rounds and, from each run's timing.toml, the time loop's phases
# of the last round (gel = diffusion; events; frames), and the CPU time the hypervisor took from
# this machine while that binary ran (steal, from /proc/stat, over all its rounds, in ticks of
# 1/100 s per CPU: a short run's one tick is a percent or more). Steal shows only time taken
# away; co-tenants' use of the shared caches and memory bandwidth, or the host's clock, do not
# show in it. Run from the repository's top folder.
set -euo pipefail
rounds=${1:?usage: $0 ROUNDS BINARY...}
shift
[ $# -ge 1 ] || { echo "usage: $0 ROUNDS BINARY..." >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# the small cube without the gel pass of every frame, as fits run it
sed 's/^record_interval_s = 0.0$/record_interval_s = 0.0\nrecord_gel = false/' \
    benches/small-cube/phantom.toml > "$work/small.toml"
# builds before 27 Nov 2026 do not know `extrapolate_holds`; false (the preset's) is their
# behaviour, so they get the preset without that line
grep -v '^extrapolate_holds' profiles/phantoms/hydrogel.toml > "$work/hydrogel-pre26.toml"
runs=(
  "fig5|--profile profiles/fig5-dive.toml --phantom profiles/phantoms/hydrogel.toml"
  "oscillation|--profile profiles/oscillation-30s.toml --phantom profiles/phantoms/oscillation.toml"
  "small-cube|--profile benches/small-cube/profile.toml --phantom $work/small.toml"
  "gf30-85-dive|--profile benches/gf30-85-dive/schedule.toml --phantom profiles/phantoms/hydrogel-dive.toml"
)
field() { sed -n "s/^$1 = //p" "$2"; }
# "steal total" ticks of all CPUs since boot (0 0 where /proc/stat is missing)
ticks() {
  if [ -r /proc/stat ]; then
    awk '/^cpu /{ print $9, $2+$3+$4+$5+$6+$7+$8+$9 }' /proc/stat
  else
    echo 0 0
  fi
}
for run in "${runs[@]}"; do
  name=${run%%|*}
  args=${run#*|}
  declare -A walls=() steal=() total=()
  for _ in $(seq "$rounds"); do
    for b in "$@"; do
      out="$work/$name-$(echo "$b" | md5sum | cut -c1-8)"
      read -r s0 t0 < <(ticks)
      # shellcheck disable=SC2086
      "$b" simulate $args --out "$out" --quiet --force > /dev/null 2>&1 ||
        "$b" simulate ${args//profiles\/phantoms\/hydrogel.toml/$work/hydrogel-pre26.toml} \
          --out "$out" --quiet --force > /dev/null
      read -r s1 t1 < <(ticks)
      steal[$b]=$(( ${steal[$b]:-0} + s1 - s0 ))
      total[$b]=$(( ${total[$b]:-0} + t1 - t0 ))
      walls[$b]="${walls[$b]:-} $(printf '%.3f' "$(field wall_seconds "$out/timing.toml")")"
    done
  done
  for b in "$@"; do
    t="$work/$name-$(echo "$b" | md5sum | cut -c1-8)/timing.toml"
    phases=""
    if grep -q '^gel_s' "$t"; then
      phases=" | gel $(field gel_s "$t") events $(field events_s "$t") frames $(field frames_s "$t")"
    fi
    stolen=""
    if [ "${total[$b]}" -gt 0 ]; then
      stolen=" | steal ${steal[$b]} of ${total[$b]} ticks"
    fi
    echo "$name $b: wall${walls[$b]} s$phases$stolen"
  done
  unset walls steal total
done
