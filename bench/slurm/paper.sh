#!/usr/bin/env bash
# bench/slurm/paper.sh [options] — submits the paper's strong-scaling runs on a Slurm cluster,
# one batch job a point (bench/slurm/coloc.sbatch: srun, SIGTERM before the time limit, the
# final checkpoint, restart), from the folder the runs go under (out/ there). The binary: $COLOC,
# else the installed one beside share/coloc/slurm, else build/coloc of the source tree, else
# coloc on PATH. Then, when they are done:
#   bench/scripts/collect.py --find out/paper --out out/paper/scaling.csv
#
#   --cases "case2 case3"          cases of bench/cases (default: the paper's cases 2 and 3)
#   --nodes "1 2 4 6 9"            node counts (default: 28 to 252 ranks on 28-core nodes)
#   --cores-per-node 28            ranks a node (one a core)
#   --modes "coupled"              run.mode of each point (case 2: dummy_dem as the paper)
#   --repeat 3                     runs a point (the scaling plots take the fastest)
#   --time 01:00:00                wall-time limit of each job
#   --out out/paper                runs in OUT/<case>-<mode>-np<ranks>-r<k>/
#   -- ...                         further options for every coloc run (--set run.steps=20, ...)
# Every sbatch command is printed before it is submitted; --dry-run prints them only.
set -euo pipefail
cases="case2 case3" nodes="1 2 4 6 9" per=28 modes="" repeat=3 time=01:00:00 out=out/paper
dry=0
extra=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --cases) cases=$2; shift 2 ;;
    --nodes) nodes=$2; shift 2 ;;
    --cores-per-node) per=$2; shift 2 ;;
    --modes) modes=$2; shift 2 ;;
    --repeat) repeat=$2; shift 2 ;;
    --time) time=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --dry-run) dry=1; shift ;;
    --) shift; extra=("$@"); break ;;
    *) echo "paper.sh: unknown option '$1' (see the head of bench/slurm/paper.sh)" >&2; exit 2 ;;
  esac
done
# bench/slurm beside bench/cases in the source tree, share/coloc/slurm beside share/coloc/cases
# installed (cmake --install)
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
casedir=$(cd "$here/../cases" && pwd)
# the job script and the binary for every job (and its resubmissions: coloc.sbatch)
export COLOC_SBATCH=$here/coloc.sbatch
if [[ -z ${COLOC:-} ]]; then
  for c in "$here/../../../bin/coloc" "$here/../../build/coloc"; do
    [[ -x $c ]] && { COLOC=$(cd "$(dirname "$c")" && pwd)/coloc; export COLOC; break; }
  done
fi
for c in $cases; do
  file=$casedir/$c.json
  [[ -f $file ]] || { echo "paper.sh: no case $file" >&2; exit 2; }
  ms=$modes
  [[ -z $ms ]] && { [[ $c == case2* ]] && ms=dummy_dem || ms=coupled; }
  for m in $ms; do
    for n in $nodes; do
      ranks=$((n * per))
      for ((k = 0; k < repeat; k++)); do
        dir=$out/$c-$m-np$ranks-r$k
        cmd=(sbatch --nodes="$n" --ntasks-per-node="$per" --time="$time"
             --job-name="coloc-$c-np$ranks" "$here/coloc.sbatch" "$file" "$dir"
             --quiet --set "run.mode=$m" "${extra[@]}")
        echo "paper.sh: ${cmd[*]}"
        ((dry)) || "${cmd[@]}"
      done
    done
  done
done
