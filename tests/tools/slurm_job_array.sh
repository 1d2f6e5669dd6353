#!/usr/bin/env bash
# The Slurm job array of docs/batch.md on a real one-node cluster: starts munged, slurmctld and
# slurmd on localhost (configuration, keys, sockets and state in a scratch folder, free ports),
# writes a database of short simulated recordings and one broken file, submits the job script
# exactly as docs/batch.md shows it (read from the page) over 3 shards and waits for them, then runs
# `s2kf summarize` and checks that every recording was tracked by exactly one task (the tasks' logs),
# the broken one is reported failed and its task FAILED, and the other tasks COMPLETED. Stops the
# daemons at exit.
#   tests/tools/slurm_job_array.sh S2KF_PROGRAM SOURCE_DIR
# Exit 77 (ctest: skipped) only where the daemons cannot be started here, with the reason.
set -euo pipefail
program=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
source_dir=$(cd "$2" && pwd)
skip() { echo "SKIPPED: $*" >&2; exit 77; }
fail() { echo "FAILED: $*" >&2; exit 1; }

for command in munged mungekey slurmctld slurmd sbatch scontrol sinfo; do
  command -v "$command" >/dev/null ||
    fail "$command is missing: install Debian's slurm-wlm and munge (scripts/test.sh does)"
done
[ "$(id -u)" -eq 0 ] || skip "slurmd starts jobs as their owner and must run as root; this runs as $(id -un)"

# A short path: munge's socket path must fit in a Unix socket address (108 bytes).
scratch=$(mktemp -d /tmp/s2kf-slurm.XXXXXX)
chmod 755 "$scratch"
export SLURM_CONF=$scratch/slurm.conf
stop() {
  if [ -f "$scratch/slurmctld.pid" ] || [ -f "$scratch/slurmd.pid" ]; then
    scontrol shutdown >/dev/null 2>&1 || true
  fi
  for daemon in slurmd slurmctld munged; do
    # Only the daemons this test started, by the pid each wrote into the scratch folder.
    if [ -f "$scratch/$daemon.pid" ]; then
      # The daemon may remove its pid file between the test above and this read.
      pid=$(cat "$scratch/$daemon.pid" 2>/dev/null) || continue
      for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; [ "$daemon" = munged ] && kill "$pid" 2>/dev/null; sleep 0.1; done
      kill -9 "$pid" 2>/dev/null || true
    fi
  done
  rm -rf "$scratch"
}
trap stop EXIT

# Free TCP ports on localhost for the controller and the node daemon.
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
ports=()
for candidate in $(shuf -i 20000-60000 -n 50); do
  port_free "$candidate" && ports+=("$candidate")
  [ ${#ports[@]} -eq 2 ] && break
done
[ ${#ports[@]} -eq 2 ] || skip "no two free TCP ports found on localhost"

mungekey --create --keyfile="$scratch/munge.key"
chmod 400 "$scratch/munge.key"
# --force: munged refuses to run as root otherwise (it only warns about it with --force).
munged --force --socket="$scratch/munge.socket" --key-file="$scratch/munge.key" --pid-file="$scratch/munged.pid" \
  --log-file="$scratch/munged.log" --seed-file="$scratch/munged.seed" ||
  skip "munged did not start: $(tail -n 3 "$scratch/munged.log" 2>/dev/null)"

host=$(hostname -s)
mkdir -p "$scratch/state" "$scratch/spool"
# Process tracking by the process tree and no task plugin: nothing here needs cgroups.
cat >"$SLURM_CONF" <<EOF
ClusterName=s2kftest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=${ports[0]}
SlurmdPort=${ports[1]}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$scratch/munge.socket
CredType=cred/munge
StateSaveLocation=$scratch/state
SlurmdSpoolDir=$scratch/spool
SlurmctldPidFile=$scratch/slurmctld.pid
SlurmdPidFile=$scratch/slurmd.pid
SlurmctldLogFile=$scratch/slurmctld.log
SlurmdLogFile=$scratch/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
ReturnToService=2
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc)
PartitionName=batch Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -f "$SLURM_CONF" || skip "slurmctld did not start: $(tail -n 3 "$scratch/slurmctld.log" 2>/dev/null)"
slurmd -f "$SLURM_CONF" || skip "slurmd did not start: $(tail -n 3 "$scratch/slurmd.log" 2>/dev/null)"
for _ in $(seq 100); do
  sinfo -h -o %t 2>/dev/null | grep -q '^idle' && break
  sleep 0.2
done
sinfo -h -o %t 2>/dev/null | grep -q '^idle' ||
  skip "the node did not come up: $(sinfo 2>&1 | tail -n 1); $(tail -n 3 "$scratch/slurmd.log" 2>/dev/null)"

# The database: five short simulated recordings in subject folders and one file that is not C3D.
database=$scratch/database
for i in 1 2 3 4 5; do
  mkdir -p "$database/S0$i"
  "$program" simulate --motion walk --frames 30 --seed "$i" --out "$database/S0$i/Walk01.c3d" >/dev/null
done
printf 'x not a C3D file\n' >"$database/S03/broken.c3d"
recordings=$(cd "$database" && find . -name '*.c3d' | sed 's|^\./||; s|\.c3d$||' | sort)
[ "$(echo "$recordings" | wc -l)" -eq 6 ] || fail "the database has $(echo "$recordings" | wc -l) recordings, not 6"

# The job script: docs/batch.md's, from its line #!/bin/bash to the end of that code block.
awk '/^#!\/bin\/bash$/ {inside = 1} inside && /^```/ {exit} inside {print}' "$source_dir/docs/batch.md" \
  >"$scratch/track.sbatch"
grep -q '^#SBATCH --array' "$scratch/track.sbatch" || fail "docs/batch.md has no job script (#!/bin/bash ... #SBATCH --array)"

# As docs/batch.md submits it, with a smaller array and one CPU per task (options given to sbatch
# override the script's #SBATCH lines); s2kf is the program under test. The test polls the
# controller every 0.2 s for the tasks' end instead of `sbatch --wait`, which sleeps 2 s and then 8 s
# between its own polls.
cd "$scratch"
mkdir -p logs
start=$(date +%s)
job=$(PATH=$(dirname "$program"):$PATH sbatch --parsable --array=0-2 --cpus-per-task=1 --time=00:10:00 \
  track.sbatch "$database/" "$scratch/results/" 2>"$scratch/sbatch.err") ||
  fail "sbatch did not submit: $(cat "$scratch/sbatch.err")"
task_states() { scontrol show job "$job" | tr ' ' '\n' | grep -E '^(ArrayTaskId|JobState|ExitCode)=' | paste - - -; }
for _ in $(seq 1500); do
  # Done once the array is split into its 3 tasks and none of them is pending or running.
  task_states >"$scratch/states"
  [ "$(wc -l <"$scratch/states")" -eq 3 ] && ! grep -qE 'JobState=(PENDING|CONFIGURING|RUNNING|COMPLETING)' "$scratch/states" && break
  sleep 0.2
done
echo "the array's tasks ended $(($(date +%s) - start)) s after submission"

# Each task's state and exit status; the failed one's log names the broken file.
cat "$scratch/states"
[ "$(wc -l <"$scratch/states")" -eq 3 ] || fail "expected 3 array tasks"
failed_task=$(grep 'JobState=FAILED' "$scratch/states" | sed 's/.*ArrayTaskId=\([0-9]*\).*/\1/')
[ "$(echo "$failed_task" | grep -c .)" -eq 1 ] || fail "expected exactly one FAILED task"
grep 'JobState=FAILED' "$scratch/states" | grep -q 'ExitCode=1:0' || fail "the FAILED task did not exit with status 1"
[ "$(grep -c 'JobState=COMPLETED.*ExitCode=0:0' "$scratch/states")" -eq 2 ] || fail "expected two COMPLETED tasks with exit status 0"
grep -q "S03/broken.c3d" "logs/s2kf_$failed_task.out" || fail "the failed task's log does not name the broken file"

# Each recording tracked by exactly one task: one "Wrote RESULTS/NAME.csv, ..." line in all the
# logs together, in the log of the task whose --shard I/3 lists it (--dry-run).
for name in $recordings; do
  [ "$name" = S03/broken ] && continue
  writers=$(grep -l "^Wrote $scratch/results/$name.csv, " logs/s2kf_*.out || true)
  [ "$(grep -c "^Wrote $scratch/results/$name.csv, " logs/s2kf_*.out | awk -F: '{n += $2} END {print n}')" -eq 1 ] ||
    fail "$name was not written exactly once (logs: $writers)"
  task=$(echo "$writers" | sed 's/.*s2kf_\([0-9]*\)\.out/\1/')
  "$program" track "$database/" --out "$scratch/results/" --shard "$task/3" --dry-run | grep -q "/$name.c3d -> " ||
    fail "$name was tracked by task $task, whose shard does not list it"
done
"$program" track "$database/" --out "$scratch/results/" --shard "$failed_task/3" --dry-run | grep -q "/S03/broken.c3d -> " ||
  fail "task $failed_task failed, but its shard does not hold broken.c3d"

# The table: one row per recording, tracked or failed.
"$program" summarize "$scratch/results/" --out "$scratch/summary.csv"
rows=$(tail -n +2 "$scratch/summary.csv" | cut -d, -f1,3 | sort)
expected=$(for name in $recordings; do
  if [ "$name" = S03/broken ]; then echo "$name,failed"; else echo "$name,tracked"; fi
done | sort)
[ "$rows" = "$expected" ] || fail "summary rows (result,status):
$rows
expected:
$expected"
for name in $recordings; do
  [ "$name" = S03/broken ] && continue
  [ -s "$scratch/results/$name.csv" ] || fail "$name.csv was not written"
done
echo "Slurm job array: 6 recordings in 3 tasks, 5 tracked, S03/broken failed in task $failed_task"
