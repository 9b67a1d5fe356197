#!/bin/sh
# Grid + time-step convergence study on the paper's full Fig. 5 dive (profiles/fig5-dive.toml through
# profiles/phantoms/hydrogel.toml): h = 346, 173, 86.5 µm with every step limit (max_step_s,
# max_pressure_change, max_content_change, bubble_tolerance, loading_tolerance: the preset's values and
# the model's defaults, src/phantom/params.rs) × 1, ½, ¼. Prints the peak radius and
# peak total volume of each level, the observed order p = log2(|f1 − f2| / |f2 − f3|) and the Richardson
# extrapolation f3 + (f3 − f2)/(2^p − 1). Usage: sh examples/fig5_convergence.sh [decophantom binary]
set -e
bin=${1:-target/release/decophantom}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
preset=profiles/phantoms/hydrogel.toml
# the preset's step cap (its [numerics] max_step_s); the other limits are the model's defaults
cap=$(sed -n 's/^max_step_s = //p' "$preset")
[ -n "$cap" ] || { echo "$preset: no max_step_s line to scale" >&2; exit 2; }
level() { # $1 grid step (m), $2 step scale
    num=$(awk -v s="$2" -v cap="$cap" 'BEGIN { printf "max_step_s = %g\\nmax_pressure_change = %g\\nmax_content_change = %g\\nbubble_tolerance = %g\\nloading_tolerance = %g", cap * s, 0.02 * s, 0.03 * s, 0.004 * s, 1e-3 * s }')
    sed -e "s/^max_step_s = .*/$num/" -e "s/^grid_step_m = .*/grid_step_m = $1/" \
        "$preset" > "$dir/p.toml"
    # every limit in place, or the study would silently run the default steps
    for key in max_step_s max_pressure_change max_content_change bubble_tolerance loading_tolerance grid_step_m; do
        [ "$(grep -c "^$key = " "$dir/p.toml")" = 1 ] || { echo "$key not set once in the scaled phantom" >&2; exit 2; }
    done
    "$bin" simulate --profile profiles/fig5-dive.toml --phantom "$dir/p.toml" \
        --out "$dir/out-$1" --quiet > /dev/null
    r=$(grep '^max_radius_m' "$dir/out-$1/summary.toml" | cut -d= -f2)
    v=$(grep '^peak_total_volume_m3' "$dir/out-$1/summary.toml" | cut -d= -f2)
    w=$(grep '^wall_seconds' "$dir/out-$1/timing.toml" | cut -d= -f2)
    echo "$1 $2 $r $v $w"
}
{
    level 346e-6 1
    level 173e-6 0.5
    level 86.5e-6 0.25
} | tee "$dir/levels" | awk '{ printf "h = %s m, step x %s: peak radius %.3f um, peak volume %.5g mm3 (%.1f s)\n", $1, $2, $3 * 1e6, $4 * 1e9, $5 }'
awk '{ r[NR] = $3; v[NR] = $4 }
END {
    for (k = 0; k < 2; k++) {
        if (k == 0) { a = r[1]; b = r[2]; c = r[3]; name = "peak radius (um)"; s = 1e6 }
        else { a = v[1]; b = v[2]; c = v[3]; name = "peak volume (mm3)"; s = 1e9 }
        q = (a - b) / (b - c)
        if (q <= 0) { printf "%s: not monotone (changes %+.3f %%, then %+.3f %%): no observed order\n", name, 100 * (b / a - 1), 100 * (c / b - 1); continue }
        p = log(q) / log(2)
        x = c + (c - b) / (2 ^ p - 1)
        printf "%s: observed order %.2f, Richardson %.5g, finest off by %+.3f %%\n", name, p, x * s, 100 * (c / x - 1)
    }
}' "$dir/levels"
