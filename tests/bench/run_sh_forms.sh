#!/usr/bin/env bash
# run_sh_forms.sh COLOC PYTHON SRC WORKDIR — bench/run.sh takes what a user types (issue 49):
#   - every `bench/run.sh ...` line of the README's code blocks runs (with --set run.steps=3 added,
#     so that it is quick), and leaves what its comment names after "->" (out/case1-np1/, ...);
#     the ranks are the line's RANKS (default 2) and coloc run's options (--set, --out,
#     --overwrite) reach coloc, --out without a second --out of the script's;
#   - `bench/run.sh` itself as a user types it, after the README's main job (it replaces those
#     runs);
#   - a second run into the same folder is refused naming --overwrite, and runs with it;
#   - no OMPI_MCA_mpi_yield_when_idle for a timing run (report.json provenance.mpi_env says
#     false), yield (and a note) with more ranks than cores, one from the environment kept;
#   - a bad CASE, a bad RANKS, --out for the main job: exit 2 with a message;
#   - the README and docs/heat.md do not call the fluid-particle heat convection unbuilt, and
#     bench/cases/bed-wall-heated.json uses it.
# bench/run.sh runs COLOC (COLOC_BINARY: nothing is built) and writes under out/ of the current
# folder, here WORKDIR.
set -u
coloc=$1 py=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work" || exit 1
cd "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
export COLOC_BINARY=$coloc
unset OMPI_MCA_mpi_yield_when_idle  # as on a user's shell; the cases below set it where they test it
runsh=$src/bench/run.sh
cores=$(nproc)
# run NAME ARGS...: bench/run.sh ARGS, output in NAME.log, status in $rc
run() {
  local name=$1
  shift
  timeout 120 bash "$runsh" "$@" > "$name.log" 2>&1
  rc=$?
  echo "== $name: exit $rc: bench/run.sh $*"
  cat "$name.log"
  [[ $rc -eq 124 ]] && fail "timed out: bench/run.sh $*"
  return 0
}
report() {  # report DIR EXPR: a Python expression over d (DIR/report.json) must hold
  [[ -f $1/report.json ]] || fail "no $1/report.json"
  "$py" -c "import json,sys; d=json.load(open(sys.argv[1])); p=d['provenance']; e=p['mpi_env']; sys.exit(0 if ($2) else 1)" \
    "$1/report.json" || fail "$1/report.json: not ($2)"
}

# The README's lines, in its ```sh blocks: bench/run.sh [ARGS] [# comment ... -> PATHS]
mapfile -t lines < <(awk '/^```sh/{f=1; next} /^```/{f=0} f && /^bench\/run\.sh( |$)/' "$src/README.md")
[[ ${#lines[@]} -ge 3 ]] || fail "the README shows ${#lines[@]} bench/run.sh lines, expected 3 or more"
k=0
for line in "${lines[@]}"; do
  cmd=${line%%#*}
  comment=${line#"$cmd"}
  read -r -a words <<< "$cmd"
  args=("${words[@]:1}")
  k=$((k + 1))
  run "readme$k" "${args[@]}" --set run.steps=3
  [[ $rc -eq 0 ]] || fail "README: $line"
  # the ranks: the line's second word when it is a number, else 2 (1 and 2 for the main job)
  ranks=2
  [[ ${#args[@]} -ge 2 && ${args[1]} =~ ^[0-9]+$ ]] && ranks=${args[1]}
  yield=False
  ((ranks > cores)) && yield=True
  ((ranks <= cores)) && grep -q "yield" "readme$k.log" && fail "README: $line: yield set for a timing run"
  # what the comment promises after "->"
  [[ $comment == *"->"* ]] || fail "README: $line: no '-> PATH' in its comment"
  IFS=',' read -r -a paths <<< "${comment#*->}"
  for p in "${paths[@]}"; do
    p=$(echo "$p" | awk '{print $1}')
    [[ -e $p ]] || fail "README: $line: no $p"
    if [[ -d $p ]]; then
      n=$ranks
      [[ ${#args[@]} -eq 0 || ${args[0]} == -* ]] && n=${p##*-np} && n=${n%/}
      report "$p" "d['run']['steps'] == 3 and d['mpi']['ranks'] == $n and e['yield_when_idle'] is $yield"
    fi
  done
done

# bench/run.sh as typed (after the README's main job above: it replaces those runs)
run plain
[[ $rc -eq 0 ]] || fail "bench/run.sh exited $rc"
report out/case1-np1 "d['status'] == 'ok' and d['mpi']['ranks'] == 1 and d['run']['sim_time'] > 0.59"
report out/case1-np2 "d['status'] == 'ok' and d['mpi']['ranks'] == 2 and e['yield_when_idle'] is False and 'bench/run.sh' not in p['command_line']"
[[ -s out/case1.png ]] || fail "no out/case1.png"
grep -q "reports in out/case1-np1/report.json and out/case1-np2/report.json" plain.log ||
  fail "bench/run.sh does not say where the reports are"

# CASE [RANKS] [options]: the same folder again is refused, --overwrite replaces it
run again2 "$src/bench/cases/case1.json" --set run.steps=3
[[ $rc -eq 2 ]] && grep -q -- "--overwrite" again2.log || fail "a second run into out/case1-np2 not refused naming --overwrite"
run again3 "$src/bench/cases/case1.json" --set run.steps=3 --overwrite
[[ $rc -eq 0 ]] || fail "--overwrite did not reach coloc run"
report out/case1-np2 "d['run']['steps'] == 3"
run own case1 1 --set run.steps=2 --out "$work/own"
[[ $rc -eq 0 ]] || fail "--out DIR (the script adds no --out of its own)"
report "$work/own" "d['mpi']['ranks'] == 1 and d['run']['steps'] == 2"
run setfirst case1 --set run.steps=2 --out "$work/s" --quiet
[[ $rc -eq 0 ]] || fail "CASE --set ... without RANKS"
report "$work/s" "d['mpi']['ranks'] == 2"

# yield: more ranks than cores, and from the environment
over=$((cores + 1))
run over case1 "$over" --set run.steps=2 --out "$work/over" --quiet
[[ $rc -eq 0 ]] || fail "$over ranks"
grep -q "oversubscribed, waiting ranks yield" over.log || fail "no note of the oversubscription"
report "$work/over" "p['oversubscribed'] is True and e['yield_when_idle'] is True and e['ranks_per_node_max'] == $over"
OMPI_MCA_mpi_yield_when_idle=1 run env case1 1 --set run.steps=2 --out "$work/env" --quiet
[[ $rc -eq 0 ]] && grep -q "OMPI_MCA_mpi_yield_when_idle=1 from the environment (kept" env.log ||
  fail "yield from the environment not kept and noted"
report "$work/env" "e['yield_when_idle'] is True"

# bad command lines
run bad1 no-such-case
[[ $rc -eq 2 ]] && grep -q "no case file 'no-such-case'" bad1.log || fail "a bad CASE"
run bad2 case1 two
[[ $rc -eq 2 ]] && grep -q "'two' is not a rank count" bad2.log || fail "a bad RANKS"
run bad3 --out x
[[ $rc -eq 2 ]] && grep -q "the main job writes out/case1-np1 and out/case1-np2" bad3.log || fail "--out for the main job"

# the feature list: heat convection is built
grep -q '"heat_transfer"' "$src/bench/cases/bed-wall-heated.json" || fail "bed-wall-heated.json has no heat_transfer"
if grep -n -i "not built yet\|convection.*not built" "$src/README.md" "$src/docs/heat.md"; then
  fail "the README or docs/heat.md calls something unbuilt (the convection is built)"
fi
echo "PASS: ${#lines[@]} README forms, bench/run.sh again, CASE [RANKS] [options], yield, bad input"
