#!/bin/sh
# The renderer's evaluation (the paper's section 6) in one run, with a Markdown report and gnuplot plots:
#   1. end-to-end time (file to PNG) against the simplification ratio, integrated and generic
#      pipelines, blunt fin 256x256 (the paper's Figure 5);
#   2. times of the stored levels of blunt fin at 128x128 (Table 2);
#   3. RMSE against the full-resolution image over ratios, volume and face sampling, blunt fin,
#      combustion and spx (Figure 8);
#   4. the cost of simplifying on the fly (a ratio between stored levels against the stored level);
#   5. peak memory (resident set) of both pipelines, on the datasets and on a large grid (the project's
#      sample shape at 160 x 96 x 72 points, 5.4 million tetrahedra, made by gtn-make-sample);
#   6. VTK's vtkUnstructuredGridVolumeRayCastMapper on the same mesh, camera and transfer function:
#      its time per frame and the RMSE between its image and ours (needs VTK's Python modules (python3-paraview) and
#      xvfb-run; skipped otherwise);
#   7. --budget-ms at a half, a quarter and a tenth of the full-resolution time.
#
# Usage: bench/render/render_bench.sh [BUILD_DIR] [DATA_DIR] [OUT_DIR]
#   (defaults: build, ../shared/data, bench-render-out). OUT_DIR receives report.md, the plots (*.png)
#   and the data tables (*.dat). SECTIONS="1 3 6" runs only some sections; RUNS=N times each point as
#   the best of N runs (default 2). Timings are wall-clock on whatever else the machine is doing.
set -eu
build=${1:-build}
data=${2:-../shared/data}
out=${3:-bench-render-out}
sections=${SECTIONS:-"1 2 3 4 5 6 7"}
runs=${RUNS:-2}
gtn="$build/gtn"
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export XDG_CACHE_HOME="$work/cache"  # a fresh time-budget calibration

want() { case " $sections " in *" $1 "*) return 0 ;; *) return 1 ;; esac; }
# jget KEY < JSON: a top-level number or string of a JSON document.
jget() { python3 -c "import json,sys; v=json.load(sys.stdin).get('$1'); print('' if v is None else v)"; }
# best_ms ARGS...: the best total_ms of $runs renders (the last run's JSON stays in $work/last.json).
best_ms() {
  best=""
  i=0
  while [ $i -lt "$runs" ]; do
    "$gtn" render "$@" --json >"$work/last.json"
    t=$(jget total_ms <"$work/last.json")
    best=$(python3 -c "print(min(float(x) for x in '$best $t'.split()))")
    i=$((i + 1))
  done
  printf '%.1f' "$best"
}
rmse() { "$gtn" compare "$1" "$2" --json | jget rmse | xargs printf '%.3f'; }
# peak resident memory (KiB) of a command
peak_kb() { /usr/bin/time -f '%M' -o "$work/time.txt" "$@" >/dev/null 2>&1; cat "$work/time.txt"; }
# peak heap (KiB) of a command: what it allocates, without the program's code and libraries, thread
# stacks and allocator arenas (valgrind's massif; empty without valgrind)
peak_heap_kb() {
  command -v valgrind >/dev/null || return 0
  valgrind --tool=massif --massif-out-file="$work/massif.out" "$@" >/dev/null 2>&1
  sed -n 's/^mem_heap_B=//p' "$work/massif.out" | sort -n | tail -1 | awk '{printf "%d", $1 / 1024}'
}

echo "converting the datasets (blunt fin and combustion 5-split, spx)..." >&2
# Blunt fin with the paper's 13 levels (Table 2: ratios 1 - 1/2^i, i = 1..13; its merges run out at level 9
# here), beyond the default storage bound of 2x level 0, which keeps levels 1-3.
"$gtn" convert "$data/plot3d/bluntfinxyz.bin" "$data/plot3d/bluntfinq.bin" --split 5 --levels 13 -o "$work/blunt.gtn" 2>/dev/null
"$gtn" convert "$data/plot3d/combxyz.bin" "$data/plot3d/combq.bin" --split 5 -o "$work/comb.gtn" 2>/dev/null
"$gtn" convert "$data/vtk/spx.vtk" -o "$work/spx.gtn" 2>/dev/null
blunt="$work/blunt.gtn"
fld="--field density"
cpu=$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //')

report="$out/report.md"
{
  echo "# Rendering benchmark"
  echo
  echo "$(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) cores ($cpu), load average $(cut -d' ' -f1-3 /proc/loadavg)."
  echo "Times are wall-clock, file to PNG, best of $runs runs (\`total_ms\` of \`gtn render --json\`)."
  echo "Datasets: blunt fin and combustion chamber (PLOT3D, 5 tetrahedra per cell), spx (and, for memory, a"
  echo "large generated grid); default transfer function (cool-warm), volume sampling unless said otherwise."
  echo
} >"$report"

if want 1; then
  echo "section 1: time against ratio..." >&2
  echo "# ratio integrated_ms generic_ms tets_decoded tets_rendered" >"$out/time_vs_ratio.dat"
  for r in 0 0.25 0.5 0.75 0.9 0.95 0.99; do
    ti=$(best_ms "$blunt" -o "$work/i.png" $fld --size 256x256 --ratio $r)
    dec=$(jget tets_decoded <"$work/last.json")
    ren=$(jget tets_rendered <"$work/last.json")
    tg=$(best_ms "$blunt" -o "$work/g.png" $fld --size 256x256 --ratio $r --pipeline generic)
    echo "$r $ti $tg $dec $ren" >>"$out/time_vs_ratio.dat"
  done
  gnuplot <<EOF
set terminal pngcairo size 640,420
set output "$out/time_vs_ratio.png"
set title "Blunt fin, 256x256: file to PNG"
set xlabel "simplification ratio"; set ylabel "ms"; set key top right; set grid
plot "$out/time_vs_ratio.dat" using 1:2 with linespoints title "integrated", \
     "" using 1:3 with linespoints title "generic"
EOF
  {
    echo "## 1. End-to-end time against simplification ratio (blunt fin, 256x256; Figure 5)"
    echo
    echo "![time against ratio](time_vs_ratio.png)"
    echo
    echo "| ratio | integrated ms | generic ms | tetrahedra decoded | rendered |"
    echo "|---|---|---|---|---|"
    grep -v '^#' "$out/time_vs_ratio.dat" | while read -r r a b c d; do echo "| $r | $a | $b | $c | $d |"; done
    echo
  } >>"$report"
fi

if want 2; then
  echo "section 2: stored levels..." >&2
  echo "# level tets integrated_ms" >"$out/levels.dat"
  i=0
  while "$gtn" render "$blunt" -o "$work/l.png" $fld --size 128x128 --level $i --json >/dev/null 2>&1; do
    t=$(best_ms "$blunt" -o "$work/l.png" $fld --size 128x128 --level $i)
    echo "$i $(jget tets_decoded <"$work/last.json") $t" >>"$out/levels.dat"
    i=$((i + 1))
  done
  gnuplot <<EOF
set terminal pngcairo size 640,420
set output "$out/levels.png"
set title "Blunt fin, 128x128: stored levels"
set xlabel "tetrahedra"; set ylabel "ms"; set grid; set key off
plot "$out/levels.dat" using 2:3 with linespoints
EOF
  {
    echo "## 2. Stored levels of blunt fin at 128x128 (Table 2)"
    echo
    echo "![levels](levels.png)"
    echo
    echo "| level | tetrahedra | integrated ms |"
    echo "|---|---|---|"
    grep -v '^#' "$out/levels.dat" | while read -r l n t; do echo "| $l | $n | $t |"; done
    echo
  } >>"$report"
fi

if want 3; then
  echo "section 3: RMSE against ratio..." >&2
  echo "# ratio blunt_volume blunt_face comb_volume comb_face spx_volume spx_face" >"$out/rmse_vs_ratio.dat"
  for s in volume face; do
    "$gtn" render "$blunt" -o "$work/blunt_full_$s.png" $fld --sampling $s
    "$gtn" render "$work/comb.gtn" -o "$work/comb_full_$s.png" $fld --sampling $s
    "$gtn" render "$work/spx.gtn" -o "$work/spx_full_$s.png" --sampling $s
  done
  for r in 0.25 0.5 0.75 0.9 0.95 0.99; do
    line="$r"
    for d in blunt comb spx; do
      f=$fld
      [ $d = spx ] && f=""
      for s in volume face; do
        "$gtn" render "$work/$d.gtn" -o "$work/r.png" $f --sampling $s --ratio $r
        line="$line $(rmse "$work/${d}_full_$s.png" "$work/r.png")"
      done
    done
    echo "$line" >>"$out/rmse_vs_ratio.dat"
  done
  gnuplot <<EOF
set terminal pngcairo size 640,420
set output "$out/rmse_vs_ratio.png"
set title "RMSE against the full-resolution image (256x256)"
set xlabel "simplification ratio"; set ylabel "RMSE (0-255)"; set key top left; set grid; set logscale y
plot "$out/rmse_vs_ratio.dat" using 1:2 w lp title "blunt fin, volume", "" using 1:3 w lp title "blunt fin, face", \
     "" using 1:4 w lp title "combustion, volume", "" using 1:5 w lp title "combustion, face", \
     "" using 1:6 w lp title "spx, volume", "" using 1:7 w lp title "spx, face"
EOF
  {
    echo "## 3. RMSE against the full-resolution image (256x256; Figure 8)"
    echo
    echo "![RMSE against ratio](rmse_vs_ratio.png)"
    echo
    echo "| ratio | blunt fin volume | blunt fin face | combustion volume | combustion face | spx volume | spx face |"
    echo "|---|---|---|---|---|---|---|"
    grep -v '^#' "$out/rmse_vs_ratio.dat" | while read -r r a b c d e f; do echo "| $r | $a | $b | $c | $d | $e | $f |"; done
    echo
  } >>"$report"
fi

if want 4; then
  echo "section 4: on-the-fly simplification..." >&2
  {
    echo "## 4. Cost of simplifying on the fly (blunt fin, 256x256)"
    echo
    echo "A ratio between stored levels decodes the finer level and applies the remaining merges on the"
    echo "fly; against rendering that stored level as is:"
    echo
    echo "| request | level | extra merges | tetrahedra rendered | integrated ms |"
    echo "|---|---|---|---|---|"
  } >>"$report"
  for req in "--level 1" "--ratio 0.6" "--ratio 0.7" "--level 2" "--ratio 0.85"; do
    t=$(best_ms "$blunt" -o "$work/o.png" $fld --size 256x256 $req)
    echo "| \`$req\` | $(jget level <"$work/last.json") | $(jget extra_merges <"$work/last.json") | $(jget tets_rendered <"$work/last.json") | $t |" >>"$report"
  done
  echo >>"$report"
fi

if want 5; then
  echo "section 5: peak memory..." >&2
  # The large grid: level 0 only (no merge tree), which is all that section renders.
  "$build/gtn-make-sample" "$work/large" 160 96 72
  "$gtn" convert "$work/large/sample.xyz" "$work/large/sample.q" --split 5 --levels 0 --no-merge-tree \
    -o "$work/large.gtn" 2>/dev/null
  rm -f "$work/large/sample.xyz" "$work/large/sample.q"
  # What any gtn process holds before it reads anything (the program and its libraries).
  base=$(peak_kb "$gtn" --version)
  {
    echo "## 5. Peak memory (resident set of the whole process, 256x256, level 0)"
    echo
    echo "\"above start\" subtracts the resident set of \`gtn --version\` ($base KiB: the program and its"
    echo "libraries), which both pipelines hold whatever the mesh."
    echo
    echo "The heap columns are the peak of what each pipeline allocates (valgrind's massif; the large grid"
    echo "is left out, as massif would take minutes on it): the resident set adds to it the program and its"
    echo "libraries, the threads' stacks and the allocator's arenas, alike in both pipelines."
    echo
    echo "| dataset | integrated KiB | generic KiB | integrated / generic | above start: integrated / generic | heap KiB: integrated / generic | heap ratio | peak tetrahedra held (integrated) | tetrahedra |"
    echo "|---|---|---|---|---|---|---|---|---|"
  } >>"$report"
  for d in blunt comb spx large; do
    f=$fld
    [ $d = spx ] && f=""
    [ $d = large ] && f="--field density"
    mi=$(peak_kb "$gtn" render "$work/$d.gtn" -o "$work/m.png" $f)
    mg=$(peak_kb "$gtn" render "$work/$d.gtn" -o "$work/m.png" $f --pipeline generic)
    hi="" hg="" hr="-"
    if [ $d != large ]; then
      hi=$(peak_heap_kb "$gtn" render "$work/$d.gtn" -o "$work/m.png" $f)
      hg=$(peak_heap_kb "$gtn" render "$work/$d.gtn" -o "$work/m.png" $f --pipeline generic)
      [ -n "$hi" ] && [ -n "$hg" ] && hr=$(python3 -c "print(f'{$hi/$hg:.3f}')")
    fi
    "$gtn" render "$work/$d.gtn" -o "$work/m.png" $f --json >"$work/last.json"
    echo "| $d | $mi | $mg | $(python3 -c "print(f'{$mi/$mg:.2f}')") | $(python3 -c "print(f'{($mi-$base)/max(1,$mg-$base):.2f}')") | ${hi:--} / ${hg:--} | $hr | $(jget peak_tets_held <"$work/last.json") | $(jget tets_decoded <"$work/last.json") |" >>"$report"
  done
  echo >>"$report"
fi

if want 6; then
  echo "section 6: VTK..." >&2
  if /usr/bin/python3 -c 'import vtk' 2>/dev/null && command -v xvfb-run >/dev/null; then
    {
      echo "## 6. VTK's vtkUnstructuredGridVolumeRayCastMapper, same mesh, camera and transfer function (256x256)"
      echo
      echo "\`gtn render --dump-view\` gives the camera and transfer function to \`bench/render/vtk_compare.py\`;"
      echo "VTK's time is per frame of the already loaded mesh (mean of 5 frames after a first one)."
      echo
      echo "| dataset | tetrahedra | VTK first frame ms | VTK ms per frame | ours, file to PNG, ms | RMSE ours vs VTK |"
      echo "|---|---|---|---|---|---|"
    } >>"$report"
    for d in blunt comb spx; do
      f=$fld
      [ $d = spx ] && f=""
      "$gtn" export "$work/$d.gtn" -o "$work/$d.vtu"
      t=$(best_ms "$work/$d.gtn" -o "$out/ours_$d.png" $f --size 256x256 --dump-view "$work/$d.view.json")
      xvfb-run -a /usr/bin/python3 "$here/vtk_compare.py" "$work/$d.vtu" "$work/$d.view.json" "$out/vtk_$d.png" \
        --frames 5 --ours "$out/ours_$d.png" --gtn "$gtn" --json >"$work/vtk.json"
      python3 - "$work/vtk.json" "$d" "$t" >>"$report" <<'EOF'
import json, sys
j = json.load(open(sys.argv[1]))
print(f"| {sys.argv[2]} | {j['tets']} | {1000 * j['first_frame_s']:.0f} | {1000 * j['mean_frame_s']:.0f} | "
      f"{sys.argv[3]} | {j['rmse']:.2f} |")
EOF
    done
    echo >>"$report"
    echo "Images: ours_*.png and vtk_*.png beside this report." >>"$report"
    echo >>"$report"
  else
    echo "## 6. VTK: skipped (VTK's Python modules or xvfb-run not installed)" >>"$report"
    echo >>"$report"
  fi
fi

if want 7; then
  echo "section 7: time budgets..." >&2
  full=$(best_ms "$blunt" -o "$work/b.png" $fld --size 256x256)
  "$gtn" render "$blunt" -o "$work/b.png" $fld --size 256x256 --budget-ms 1 >/dev/null 2>&1  # calibrate
  {
    echo "## 7. Time budgets (blunt fin, 256x256; full resolution ${full} ms)"
    echo
    echo "| budget | ms | runs within budget + 10% | plans chosen (level+merges on the fly) | times (ms) |"
    echo "|---|---|---|---|---|"
  } >>"$report"
  for frac in 2 4 10; do
    b=$(python3 -c "print(f'{$full / $frac:.1f}')")
    ok=0
    times=""
    levels=""
    n=0
    while [ $n -lt 10 ]; do
      "$gtn" render "$blunt" -o "$work/b.png" $fld --size 256x256 --budget-ms "$b" --json >"$work/last.json"
      t=$(jget total_ms <"$work/last.json")
      times="$times $(printf '%.0f' "$t")"
      levels="$levels $(jget level <"$work/last.json")+$(jget extra_merges <"$work/last.json")"
      ok=$((ok + $(python3 -c "print(1 if $t <= 1.1 * $b else 0)")))
      n=$((n + 1))
    done
    echo "| 1/$frac | $b | $ok of 10 | $(echo $levels | tr ' ' '\n' | sort -u | tr '\n' ' ') |$times |" >>"$report"
  done
  echo >>"$report"
fi

echo "wrote $report" >&2
