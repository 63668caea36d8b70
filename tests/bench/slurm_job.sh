#!/usr/bin/env bash
# slurm_job.sh COLOC MPIEXEC PYTHON CASE SRC WORKDIR — bench/slurm/coloc.sbatch and paper.sh with a
# fake srun and sbatch on PATH (issue 49; docs/cluster.md):
#   1. the job script, run as Slurm runs a batch job (SLURM_* set, in the submit folder): its
#      srun gets coloc run CASE --out OUT; the fake srun sends SIGTERM to every rank mid-run, as
#      #SBATCH --signal=TERM@... makes Slurm do; coloc writes the checkpoint of its last step and
#      report.json "interrupted" and exits 143; the script submits itself again (the fake
#      sbatch records the command: the same script, CASE, OUT and options, the same node and
#      task counts, after this job, one resubmission fewer);
#   2. that submission run as the next job: srun with --restart of the checkpoint the report
#      names; the run ends "ok" at run.steps, its log continued; no more submission;
#   3. a third job finds the run complete and does nothing; a failed run stops the chain;
#   4. the script asks Slurm for SIGTERM to the tasks (not B:) before the limit;
#   5. paper.sh submits one job a case, mode, node count and repeat, each through coloc.sbatch.
set -u
coloc=$1 mpiexec=$2 py=$3 case=$4 src=$5 work=$6
rm -rf "$work" && mkdir -p "$work/bin" || exit 1
work=$(realpath "$work")
fail() { echo "FAIL: $*"; exit 1; }
job=$src/bench/slurm/coloc.sbatch

# The fake srun: mpiexec -n $SLURM_NTASKS; with FAKE_SIGTERM=1 it sends SIGTERM to every rank
# once the run's series.csv holds its first steps (what Slurm's --signal=TERM@s does to each task).
cat > "$work/bin/srun" <<EOF
#!/usr/bin/env bash
echo "srun \$*" >> "$work/srun.calls"
while [[ \$1 == --* ]]; do shift; done   # --cpu-bind, --kill-on-bad-exit: Slurm's
out=
for ((i = 1; i <= \$#; i++)); do [[ \${!i} == --out ]] && { j=\$((i + 1)); out=\${!j}; }; done
"$mpiexec" -n "\${SLURM_NTASKS:-2}" --bind-to none "\$@" &
mpi=\$!
if [[ \${FAKE_SIGTERM:-0} == 1 ]]; then
  for _ in \$(seq 300); do
    sleep 0.1
    rows=\$(wc -l 2>/dev/null < "\$out/series.csv")
    [[ \${rows:-0} -ge 5 ]] && break
  done
  for p in \$(pgrep -P \$mpi); do kill -TERM \$p; done
fi
wait \$mpi
EOF
cat > "$work/bin/sbatch" <<EOF
#!/usr/bin/env bash
printf '%s\n' "COLOC_RESUBMIT=\${COLOC_RESUBMIT:-}" "\$@" > "$work/sbatch.\$(date +%s%N)"
echo "Submitted batch job 4242"
EOF
chmod +x "$work/bin/srun" "$work/bin/sbatch"
export PATH=$work/bin:$PATH

grep -qx "#SBATCH --signal=TERM@[0-9]*" "$job" || fail "no '#SBATCH --signal=TERM@SECONDS' (to the tasks)"

cd "$work" || exit 1
export SLURM_SUBMIT_DIR=$src SLURM_JOB_NUM_NODES=1 SLURM_NTASKS=2 SLURM_JOB_NAME=coloc-test
export COLOC=$coloc COLOC_RESUBMIT=2 OMPI_MCA_mpi_yield_when_idle=1
steps=600
opts=(--set run.steps=$steps --quiet)

# 1. the first job: stopped by SIGTERM, resubmitted
SLURM_JOB_ID=101 FAKE_SIGTERM=1 timeout 120 bash "$job" "$case" out/run "${opts[@]}" > job1.log 2>&1
rc=$?
cat job1.log
[[ $rc -eq 0 ]] || fail "the first job exited $rc (expected 0: stopped and resubmitted)"
grep -q "srun --cpu-bind=cores" srun.calls || fail "the job did not start coloc through srun"
grep -q "coloc: stopped by SIGTERM after step" out/run/log.txt || fail "coloc was not stopped by SIGTERM"
read -r status ck step < <("$py" -c 'import json,sys; d=json.load(open(sys.argv[1])); print(d["status"], d.get("checkpoint"), d["run"]["steps"])' out/run/report.json)
[[ $status == interrupted ]] || fail "report.json status $status, expected interrupted"
[[ -f $ck ]] || fail "no checkpoint $ck"
((step > 0 && step < steps)) || fail "stopped at step $step of $steps"
subs=(sbatch.*)
[[ ${#subs[@]} -eq 1 && -f ${subs[0]} ]] || fail "${#subs[@]} submissions, expected 1"
mapfile -t sub < "${subs[0]}"
printf 'resubmitted: %s\n' "${sub[*]}"
expected=(COLOC_RESUBMIT=1 --export=ALL --dependency=afterany:101 --nodes=1 --ntasks=2
          --job-name=coloc-test "$src/bench/slurm/coloc.sbatch" "$case" out/run "${opts[@]}")
[[ "${sub[*]}" == "${expected[*]}" ]] || fail "resubmitted as: ${sub[*]}
expected: ${expected[*]}"

# 2. the resubmitted job: continues from the checkpoint to the end
export COLOC_RESUBMIT=1
SLURM_JOB_ID=102 timeout 180 bash "$job" "$case" out/run "${opts[@]}" > job2.log 2>&1
rc=$?
cat job2.log
[[ $rc -eq 0 ]] || fail "the second job exited $rc"
grep -q "continuing out/run from $ck" job2.log || fail "no restart from $ck"
grep -q -- "--restart $ck" srun.calls || fail "srun did not get --restart $ck"
"$py" - out/run/report.json "$steps" "$step" <<'EOF' || fail "the continued run's report"
import json, sys
d, steps, step = json.load(open(sys.argv[1])), int(sys.argv[2]), int(sys.argv[3])
assert d["status"] == "ok", d["status"]
assert d["run"]["steps"] == steps and d["run"]["first_step"] == step, d["run"]
assert d["restart"], "no restart object"
print("continued from step", step, "to", steps)
EOF
grep -q "^coloc: ---- the run continues (--restart) ----" out/run/log.txt || fail "the log did not go on"
[[ $(ls sbatch.* | wc -l) -eq 1 ]] || fail "a finished run was submitted again"

# 3. a job for a complete run does nothing; a failed run stops the chain
SLURM_JOB_ID=103 bash "$job" "$case" out/run "${opts[@]}" > job3.log 2>&1 || fail "job 3 exited $?"
grep -q "the run is complete; nothing to do" job3.log || { cat job3.log; fail "job 3 ran again"; }
mkdir -p out/bad && echo '{"status": "failed"}' > out/bad/report.json
SLURM_JOB_ID=104 bash "$job" "$case" out/bad > job4.log 2>&1
[[ $? -eq 1 ]] && grep -q "the run failed; see out/bad/log.txt" job4.log || { cat job4.log; fail "a failed run"; }
bash "$job" "$case" out/x --out y > job5.log 2>&1
[[ $? -eq 2 ]] && grep -q -- "--out: the job gives --out OUT and --restart itself" job5.log ||
  { cat job5.log; fail "--out among the options"; }
[[ $(ls sbatch.* | wc -l) -eq 1 ]] || fail "submitted again"

# 5. the paper's campaign: one job a point
rm -f sbatch.*
bash "$src/bench/slurm/paper.sh" --nodes "1 2" --repeat 2 --out out/paper -- --set run.steps=5 \
  > paper.log 2>&1 || { cat paper.log; fail "paper.sh exited $?"; }
cat paper.log
n=$(ls sbatch.* | wc -l)
[[ $n -eq 8 ]] || fail "paper.sh submitted $n jobs, expected 8 (2 cases x 2 node counts x 2)"
for f in sbatch.*; do
  grep -qx "$src/bench/slurm/coloc.sbatch" "$f" || fail "$f: not through coloc.sbatch"
  c=$(grep -x ".*/bench/cases/case[23].json" "$f") && [[ -f $c ]] || fail "$f: no case file"
  grep -qx -- "--ntasks-per-node=28" "$f" || fail "$f: not 28 tasks a node"
  grep -qx -- "--set" "$f" && grep -qx "run.steps=5" "$f" || fail "$f: the extra options are lost"
done
grep -lx -- "--nodes=2" sbatch.* | xargs grep -lx "out/paper/case3-coupled-np56-r1" > /dev/null ||
  fail "no case3 job on 2 nodes (56 ranks), repeat 1"
grep -lx "run.mode=dummy_dem" sbatch.* | xargs grep -l "case2.json" > /dev/null ||
  fail "case 2 not run as dummy_dem"
echo "PASS: the job stopped at step $step by SIGTERM, resubmitted itself, continued to $steps"
