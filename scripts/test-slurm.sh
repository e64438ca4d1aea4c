#!/usr/bin/env bash
# A real one-node Slurm cluster on this machine, to test the sharded render
# end to end: installs Debian's slurm-wlm and munge when missing (apt-get, as
# root), writes a one-node slurm.conf (this host, 2 CPUs, no cgroups, every
# state directory under a temporary directory), creates a munge key, starts
# munged, slurmctld and slurmd directly (no systemd), submits
# examples/slurm/render.sbatch (an array of 4 shards of the Cornell box at a
# small size) and examples/slurm/merge.sbatch (--dependency=afterok, waited
# for with sbatch --wait), and checks that the merged PNG is byte-identical to
# a single-process render. The daemons it started are stopped on exit.
#
#   scripts/test-slurm.sh [path/to/caustic]   (default: the release build)
#
# Environment: SHARD_BY=samples tests the other mode (the PNG is then only
# compared within the merge bound, see docs/cluster.md, so cmp is skipped);
# KEEP=1 keeps the temporary directory.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

caustic=${1:-${CARGO_TARGET_DIR:-$root/target}/release/caustic}
if [ ! -x "$caustic" ]; then
  echo "test-slurm: no caustic binary at $caustic (cargo build --release first)" >&2
  exit 1
fi
caustic=$(realpath "$caustic")

need=()
for cmd in munged slurmctld slurmd sbatch; do
  command -v "$cmd" >/dev/null 2>&1 || need+=("$cmd")
done
if [ ${#need[@]} -gt 0 ]; then
  if [ "$(id -u)" != 0 ]; then
    echo "test-slurm: ${need[*]} missing and not root: install slurm-wlm and munge" >&2
    exit 1
  fi
  echo "test-slurm: installing slurm-wlm and munge"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

tmp=$(mktemp -d /tmp/caustic-slurm.XXXXXX)
chmod 755 "$tmp"
pids=()
cleanup() {
  local status=$?
  for pid in "${pids[@]}"; do
    kill "$pid" 2>/dev/null || true
  done
  for pid in "${pids[@]}"; do
    # Wait (a few seconds at most) for each daemon we started to exit.
    for _ in $(seq 50); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.1
    done
    kill -9 "$pid" 2>/dev/null || true
  done
  if [ $status -ne 0 ]; then
    echo "test-slurm: FAILED; logs:" >&2
    for log in "$tmp"/log/*.log "$tmp"/work/*.out; do
      [ -f "$log" ] && { echo "== $log" >&2; tail -n 20 "$log" >&2; }
    done
  fi
  if [ "${KEEP:-0}" = 1 ]; then
    echo "test-slurm: kept $tmp" >&2
  else
    rm -rf "$tmp"
  fi
  exit $status
}
trap cleanup EXIT INT TERM

mkdir -p "$tmp"/{munge,log,state,spool,work}
host=$(hostname -s)
user=$(id -un)

# munge: a fresh key and a private socket, so no system munged is touched.
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 755 "$tmp/munge"
chmod 400 "$tmp/munge/munge.key"
if id munge >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
  chown -R munge:munge "$tmp/munge"
  munge_user=(runuser -u munge --)
else
  munge_user=()
fi
socket="$tmp/munge/munge.socket"
"${munge_user[@]}" munged --foreground --force --key-file="$tmp/munge/munge.key" --socket="$socket" \
  --pid-file="$tmp/munge/munged.pid" --seed-file="$tmp/munge/munged.seed" \
  --log-file="$tmp/munge/munged.log" >"$tmp/log/munged.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do [ -S "$socket" ] && break; sleep 0.1; done
[ -S "$socket" ] || { echo "test-slurm: munged did not start" >&2; exit 1; }

# Free ports for the two daemons (another Slurm on the machine keeps its own).
port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
ctld_port=$(port)
cpus=$(nproc)
[ "$cpus" -gt 2 ] && cpus=2  # the one-node cluster of 2 CPUs (fewer if the machine has fewer)
slurmd_port=$(port)
cat >"$tmp/slurm.conf" <<EOF
ClusterName=caustic-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$user
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$tmp/slurm.conf

slurmctld -D -i -f "$SLURM_CONF" >"$tmp/log/slurmctld.stdout" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" >"$tmp/log/slurmd.stdout" 2>&1 &
pids+=($!)
for _ in $(seq 100); do
  state=$(sinfo -h -n "$host" -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 0.2
done
[ "$state" = idle ] || { echo "test-slurm: the node is not idle (state: ${state:-none})" >&2; exit 1; }
echo "test-slurm: cluster up (node $host, $cpus CPUs, slurmctld port $ctld_port)"

# The render: 4 shards of the Cornell box, small.
export CAUSTIC=$caustic
export SCENE=$root/scenes/cornell.toml
export PARTS=$tmp/work/parts
export OUTPUT=$tmp/work/merged.png
export SHARD_BY=${SHARD_BY:-tiles}
export CAUSTIC_ARGS="--width 160 --height 120 --spp 8 --photons 50000"
cd "$tmp/work"
start=$(date +%s)
jid=$(sbatch --parsable "$root/examples/slurm/render.sbatch")
echo "test-slurm: array job $jid submitted (4 shards by $SHARD_BY)"
sbatch --wait --dependency="afterok:$jid" "$root/examples/slurm/merge.sbatch" >/dev/null
end=$(date +%s)
sacct_state=$(squeue -h -j "$jid" 2>/dev/null | wc -l)
[ "$sacct_state" = 0 ] || { echo "test-slurm: the array is still queued" >&2; exit 1; }
ls "$PARTS" | sort | tr '\n' ' '
echo
[ -f "$OUTPUT" ] || { echo "test-slurm: the merge job wrote no $OUTPUT" >&2; exit 1; }

# shellcheck disable=SC2086
"$caustic" render "$SCENE" $CAUSTIC_ARGS --threads 2 --quiet -o "$tmp/work/single.png" >/dev/null
if [ "$SHARD_BY" = tiles ]; then
  cmp "$OUTPUT" "$tmp/work/single.png"
  echo "test-slurm: PASS: merged PNG of 4 Slurm array tasks is byte-identical to the single-process render" \
    "($((end - start)) s through Slurm)"
else
  echo "test-slurm: PASS: 4 sample shards merged through Slurm (within the bound of docs/cluster.md, which tests/shards.rs checks)"
fi

# Again with the photons traced once (caustic photons) and loaded by every task.
# shellcheck disable=SC2086
"$caustic" photons "$SCENE" $CAUSTIC_ARGS --quiet -o "$tmp/work/photons.bin"
export PHOTON_MAP=$tmp/work/photons.bin PARTS=$tmp/work/parts-map OUTPUT=$tmp/work/merged-map.png
jid=$(sbatch --parsable "$root/examples/slurm/render.sbatch")
sbatch --wait --dependency="afterok:$jid" "$root/examples/slurm/merge.sbatch" >/dev/null
if [ "$SHARD_BY" = tiles ]; then
  cmp "$OUTPUT" "$tmp/work/single.png"
  echo "test-slurm: PASS: the same with --photon-map (array job $jid), byte-identical"
fi
unset PHOTON_MAP

# The workstation way (docs/cluster.md): xargs -P, same bytes.
mkdir -p "$tmp/work/xargs" && cd "$tmp/work/xargs"
# shellcheck disable=SC2086
seq 0 3 | xargs -P 2 -I{} "$caustic" render "$SCENE" --shard {}/4 --threads 1 --quiet -o part-{}.exr $CAUSTIC_ARGS >/dev/null
"$caustic" merge part-*.exr -o merged.png --quiet
cmp merged.png "$tmp/work/single.png"
echo "test-slurm: PASS: xargs -P shards merge byte-identical too"

# The Kubernetes manifest cannot run here: check that it is valid YAML.
if ! python3 -c 'import yaml' 2>/dev/null; then
  python3 -m pip install -q pyyaml 2>/dev/null || python3 -m pip install -q --break-system-packages pyyaml
fi
python3 - "$root/examples/k8s/indexed-job.yaml" <<'PY'
import sys, yaml
docs = [d for d in yaml.safe_load_all(open(sys.argv[1])) if d]
kinds = [d["kind"] for d in docs]
assert kinds == ["PersistentVolumeClaim", "Job", "Job"], kinds
shards = docs[1]["spec"]
assert shards["completionMode"] == "Indexed", shards
assert "--shard-count 4" in shards["template"]["spec"]["containers"][0]["args"][0]
assert shards["completions"] == 4
print("test-slurm: PASS: examples/k8s/indexed-job.yaml is valid YAML (an Indexed Job of 4 and a merge Job)")
PY
