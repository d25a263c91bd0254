#!/usr/bin/env bash
# End-to-end test of submit.sh on a real one-node Slurm cluster that this script starts and
# stops itself (as root, no systemd): munged, slurmctld and slurmd from Debian's slurm-wlm and
# munge packages (installed with apt-get when missing), a minimal slurm.conf in a temporary
# folder, the daemons stopped by their pid files on exit. Then:
#   1. phong at 1024x768 over 4 array tasks + the merge job (submit.sh --wait) equals the
#      single-machine render byte for byte;
#   2. a split the image cannot take (4 tasks, 2 bands of rows) fails its tasks, the merge
#      is cancelled, and submit.sh --wait exits non-zero.
# About 20-40 s once the packages are installed. Run from anywhere:
#   contrib/slurm/test-cluster.sh            (builds target/release/whitted if needed)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)

[[ $(id -u) == 0 ]] || { echo "test-cluster.sh: needs root (it starts munged and slurmd)" >&2; exit 2; }
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi
export WHITTED=${WHITTED:-$root/target/release/whitted}
[[ -x $WHITTED ]] || (cd "$root" && cargo build --release --bin whitted)

tmp=$(mktemp -d /tmp/whitted-slurm.XXXXXX)
chmod 755 "$tmp"
pids=("$tmp/slurmd.pid" "$tmp/slurmctld.pid" "$tmp/munged.pid")
stop() {
    local status=$?
    for f in "${pids[@]}"; do
        if [[ -s $f ]]; then
            local pid
            pid=$(cat "$f")
            kill "$pid" 2>/dev/null || true
            for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        fi
    done
    if [[ $status != 0 ]]; then
        echo "--- slurmctld log" >&2; tail -n 20 "$tmp/slurmctld.log" >&2 || true
        echo "--- slurmd log" >&2; tail -n 20 "$tmp/slurmd.log" >&2 || true
        for f in "$tmp"/out*/slurm-*.out; do [[ -f $f ]] && { echo "--- $f" >&2; cat "$f" >&2; }; done
    fi
    rm -rf "$tmp"
    exit "$status"
}
trap stop EXIT

# munge: a key (made once), the daemon as the munge user
[[ -f /etc/munge/munge.key ]] || mungekey --create
chown munge:munge /etc/munge/munge.key
mkdir -p /run/munge /var/lib/munge /var/log/munge
chown munge:munge /run/munge /var/lib/munge /var/log/munge
chown munge:munge "$tmp"
runuser -u munge -- munged --pid-file="$tmp/munged.pid" --log-file="$tmp/munged.log"
chown root:root "$tmp"
for _ in $(seq 50); do [[ -S /run/munge/munge.socket.2 ]] && break; sleep 0.1; done

host=$(hostname)
cat >"$tmp/slurm.conf" <<CONF
ClusterName=whitted-test
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=main Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
mkdir -p "$tmp/state" "$tmp/spool"
export SLURM_CONF=$tmp/slurm.conf
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 100); do
    [[ $(sinfo -h -o %T 2>/dev/null) == idle ]] && break
    sleep 0.2
done
[[ $(sinfo -h -o %T) == idle ]] || { echo "test-cluster.sh: the node never became idle" >&2; exit 1; }

echo "1. phong over 4 array tasks"
size=(--width 1024 --height 768)
"$here/submit.sh" --wait phong "$tmp/out" 4 "${size[@]}"
"$WHITTED" render phong "${size[@]}" -q -o "$tmp/single.exr"
cmp "$tmp/out/phong.exr" "$tmp/single.exr"
echo "   merged image == single-machine render"

echo "2. a split the image cannot take fails, and --wait says so"
if "$here/submit.sh" --wait phong "$tmp/out-bad" 4 --width 32 --height 24; then
    echo "test-cluster.sh: submit.sh --wait succeeded though its tasks failed" >&2
    exit 1
fi
[[ ! -e $tmp/out-bad/phong.exr ]]
grep -q "only 2 bands" "$tmp"/out-bad/slurm-*_3.out
echo "   tasks failed, merge cancelled, exit status non-zero"
echo "test-cluster.sh: ok"
