#!/usr/bin/env bash
# Behaviour unchanged? Runs two builds of the `tridex` command on the same inputs and compares
# what they write, byte for byte: the bundled example and its rotary twin (STL, PNG, report,
# HTML page, `check` against the first result), `moves` and `groups` of every program under
# gcode/examples and tests/data/gcode, and bench/raster_program.py's raster with each cutter.
# Reports are compared without their timings and memory figures, which vary from run to run.
#
#   tools/compare_outputs.sh OLD/tridex NEW/tridex [WORKDIR]    exit 0 when everything matches
#
# For a refactoring that must not change behaviour (issue 35): build the commit before and after.
set -uo pipefail
cd "$(dirname "$0")/.."
old=$(realpath "$1") new=$(realpath "$2")
work=${3:-$(mktemp -d /tmp/tridex-compare.XXXXXX)}
mkdir -p "$work/old" "$work/new" "$work/raster"
python3 bench/raster_program.py "$work/raster" > /dev/null

# Strips the figures that change between two runs of one binary from a JSON report or page.
strip_volatile() {
  python3 - "$1" <<'EOF'
import json, re, sys
path = sys.argv[1]
text = open(path, encoding="utf-8", errors="surrogateescape").read()
VOLATILE = {"timings_s", "peak_memory_mib", "peak_rss_mib", "memory_estimate_mib", "memory", "elapsed_s", "threads", "generated"}
def scrub(v):
    if isinstance(v, dict):
        return {k: scrub(x) for k, x in v.items() if k not in VOLATILE}
    if isinstance(v, list):
        return [scrub(x) for x in v]
    return v
try:
    out = json.dumps(scrub(json.loads(text)), sort_keys=True)
except ValueError:  # a page: the same keys inside its embedded JSON
    out = re.sub(r'"(timings_s|peak_memory_mib|peak_rss_mib|memory_estimate_mib|memory|elapsed_s|threads|generated)":\s*(\{[^{}]*\}|[^,}]*)', '"\\1":_', text)
out = re.sub(r"/(old|new)/", "/SIDE/", out)  # each side writes to its own folder
open(path, "w", encoding="utf-8", errors="surrogateescape").write(out)
EOF
}

run_both() {  # NAME ARGS... (each "@OUT" in ARGS becomes the side's output folder)
  local name=$1; shift
  for side in old new; do
    local bin=$old; [ $side = new ] && bin=$new
    local args=("${@//@OUT/$work/$side}")
    "$bin" "${args[@]}" > "$work/$side/$name.stdout" 2> "$work/$side/$name.stderr"
    echo "exit $?" >> "$work/$side/$name.stdout"
    sed -i -E "s|$work/$side/|@OUT/|g; s/[0-9]+(\.[0-9]+)? ?(s|ms|MiB|GiB)\b/#/g" "$work/$side/$name.stdout" "$work/$side/$name.stderr"
  done
}

ex=gcode/examples
run_both example simulate $ex/mold_3plus2.camotics -o @OUT/example.stl --png @OUT/example.png \
  --report @OUT/example.json --html @OUT/example.html
run_both twin simulate $ex/mold_3plus2_bc.nc --machine bc-trunnion --tools $ex/mold_3plus2.tools.json \
  --stock box:0,0,0,100,80,50 -o @OUT/twin.stl --report @OUT/twin.json
run_both check check $ex/mold_3plus2.camotics --design "$work/old/example.stl" \
  --report @OUT/check.json --html @OUT/check.html -o @OUT/check.stl
for cutter in ball flat bull; do
  run_both raster_$cutter simulate "$work/raster/raster.nc" --tools "$work/raster/tools_$cutter.json" \
    --stock box:0,0,0,100,100,25 --zmap-cell 0.05 -o @OUT/raster_$cutter.stl --report @OUT/raster_$cutter.json
done
while IFS= read -r program; do
  key=$(echo "$program" | tr '/.' '__')
  machine=(); case "$program" in *linuxcnc*) machine=(--machine linuxcnc) ;; esac
  case "$program" in *_bc.nc) machine=(--machine bc-trunnion) ;; esac
  run_both "moves_$key" moves "$program" "${machine[@]}" -o @OUT/moves_$key.jsonl
  run_both "groups_$key" groups "$program" "${machine[@]}" -o @OUT/groups_$key.json
done < <(find $ex tests/data/gcode -type f \( -name '*.nc' -o -name '*.ngc' -o -name '*.camotics' -o -name '*.gcode' -o -name '*.tap' \) | sort)

for f in "$work"/old/*.json "$work"/old/*.html; do
  [ -f "$f" ] && strip_volatile "$f"
  [ -f "$work/new/${f##*/}" ] && strip_volatile "$work/new/${f##*/}"
done
differ=0 same=0
for f in "$work"/old/*; do
  g="$work/new/${f##*/}"
  if cmp -s "$f" "$g"; then same=$((same + 1)); else differ=$((differ + 1)); echo "differs: ${f##*/}"; fi
done
for g in "$work"/new/*; do [ -e "$work/old/${g##*/}" ] || { differ=$((differ + 1)); echo "only new: ${g##*/}"; }; done
echo "compare_outputs: $same the same, $differ different ($work)"
[ $differ -eq 0 ]
