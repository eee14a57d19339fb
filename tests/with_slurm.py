#!/usr/bin/python3
"""Runs a command beside a throwaway single-node Slurm cluster (Debian's slurm-wlm and munge), then stops it.

usage: with_slurm.py COMMAND [ARGS...]

Everything lives in one temporary folder: munged with its own key, socket, pid, log and seed files;
slurmctld and slurmd with a generated slurm.conf (free ports, state, spool, pid and log files all in
the folder; the node as `slurmd -C` sees this machine; proctrack/linuxproc, task/none, no cgroups, no
accounting). The daemons run as the user that runs this script (SlurmUser; as root, root: slurmd can
only start jobs for its own user unless it is root), so the command's jobs run as that user. The command gets SLURM_CONF (the generated file),
BOKEH_TEST_SLURM_CONF (the same; tests skip without it), BOKEH_TEST_SLURM_DIR (the folder) and PATH
with the Slurm clients first, and no SLURM_*/SBATCH_*/SQUEUE_* variables from an enclosing allocation,
so that sbatch, squeue, scancel and scontrol talk to this cluster only. Its exit status is this
script's. At the end, whether the command passed, failed or was interrupted (SIGTERM), every job is
cancelled, the daemons are stopped (and killed if they do not stop), any process still holding the
cluster's SLURM_CONF is killed, and the folder is removed. With no Slurm installed, the command runs
without the variables (its Slurm tests then skip, saying why) and this says so.
"""
import os
import pwd
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

SBIN = ("/usr/sbin", "/usr/local/sbin", "/sbin")
START_TIMEOUT_S = 60  # a bound on waiting for a daemon, not an expected time


def find(name, dirs=()):
    for d in dirs:
        path = os.path.join(d, name)
        if os.access(path, os.X_OK):
            return path
    return shutil.which(name)


def free_ports(count):
    """Ports nothing listens on now (bound to port 0 together, then released)."""
    socks = []
    try:
        for _ in range(count):
            s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            s.bind(("", 0))
            socks.append(s)
        return [s.getsockname()[1] for s in socks]
    finally:
        for s in socks:
            s.close()


def read_pid(path):
    try:
        return int(open(path).read().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def alive(pid):
    if pid is None:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:  # a zombie (exited, not yet reaped by its parent) is gone for our purposes
        return open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


def wait_gone(pids, timeout_s):
    end = time.monotonic() + timeout_s
    while any(alive(p) for p in pids) and time.monotonic() < end:
        time.sleep(0.1)
    return [p for p in pids if alive(p)]


def processes_of(conf):
    """Processes started for this cluster: their environment holds its SLURM_CONF (the daemons, slurmstepd,
    the jobs and their children all inherit it)."""
    marker = f"SLURM_CONF={conf}".encode()
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        try:
            with open(f"/proc/{entry}/environ", "rb") as f:
                if marker in f.read().split(b"\0"):
                    found.append(int(entry))
        except OSError:
            pass
    return found


def main(argv):
    if not argv:
        sys.exit(__doc__)
    tools = {name: find(name, SBIN) for name in ("munged", "slurmctld", "slurmd")}
    tools.update({name: find(name) for name in ("munge", "unmunge", "sbatch", "squeue", "scancel", "scontrol", "sinfo")})
    missing = sorted(name for name, path in tools.items() if path is None)
    if missing:
        print(f"with_slurm.py: no Slurm installed (missing {', '.join(missing)}; apt-get install slurmctld slurmd "
              "slurm-client munge): running without it", flush=True)
        return subprocess.call(argv)

    user = pwd.getpwuid(os.geteuid()).pw_name
    folder = tempfile.mkdtemp(prefix="bokeh_slurm_")
    os.chmod(folder, 0o755)  # munged: every folder above its socket must be executable by all, writable by none
    munge_dir = os.path.join(folder, "munge")
    os.mkdir(munge_dir, 0o755)
    sock = os.path.join(munge_dir, "munge.socket")
    key = os.path.join(munge_dir, "munge.key")
    munged_pid_file = os.path.join(munge_dir, "munged.pid")
    conf = os.path.join(folder, "slurm.conf")
    ctld_pid_file, slurmd_pid_file = os.path.join(folder, "slurmctld.pid"), os.path.join(folder, "slurmd.pid")
    logs = [os.path.join(munge_dir, "munged.log"), os.path.join(folder, "slurmctld.log"), os.path.join(folder, "slurmd.log")]
    env = {k: v for k, v in os.environ.items() if not k.startswith(("SLURM_", "SBATCH_", "SQUEUE_", "SALLOC_", "SRUN_"))}
    env["SLURM_CONF"] = conf
    clients = os.path.dirname(tools["sbatch"])
    env["PATH"] = clients + os.pathsep + env.get("PATH", "/usr/bin:/bin")
    started = []  # pid files of the daemons started

    def quiet(cmd, timeout=30):
        try:
            return subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                  timeout=timeout)
        except subprocess.TimeoutExpired as e:
            return subprocess.CompletedProcess(cmd, 124, f"timed out after {e.timeout} s")

    def stop():
        if os.path.exists(ctld_pid_file) and alive(read_pid(ctld_pid_file)):
            # Every job of this cluster, then the daemons; slurmstepd outlives slurmd, so jobs go first.
            quiet([tools["scancel"], "--full", "--user", user], timeout=20)
            end = time.monotonic() + 20
            while time.monotonic() < end:
                q = quiet([tools["squeue"], "--noheader", "--states=all", "--format=%i %T"], timeout=10)
                if q.returncode != 0 or not any(word in q.stdout for word in ("RUNNING", "COMPLETING", "PENDING",
                                                                              "CONFIGURING", "SUSPENDED")):
                    break
                time.sleep(0.3)
            quiet([tools["scontrol"], "shutdown"], timeout=20)
        pids = [read_pid(p) for p in (ctld_pid_file, slurmd_pid_file) if p in started]
        left = wait_gone([p for p in pids if p], 15)
        for pid in left:
            print(f"with_slurm.py: daemon {pid} did not stop: killing it", file=sys.stderr)
            os.kill(pid, signal.SIGKILL)
        munged_pid = read_pid(munged_pid_file) if munged_pid_file in started else None
        stray = [p for p in processes_of(conf) if p != munged_pid]
        for pid in stray:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        if stray:
            print(f"with_slurm.py: killed {len(stray)} process(es) still holding this cluster's SLURM_CONF", file=sys.stderr)
        wait_gone(stray, 10)
        if munged_pid and alive(munged_pid):
            os.kill(munged_pid, signal.SIGTERM)
            if wait_gone([munged_pid], 10):
                os.kill(munged_pid, signal.SIGKILL)
        shutil.rmtree(folder, ignore_errors=True)

    def fail(what, detail=""):
        for log in logs:
            if os.path.exists(log):
                tail = open(log, errors="replace").read().splitlines()[-30:]
                print(f"--- {log} (last {len(tail)} lines)", *tail, sep="\n", file=sys.stderr)
        print(f"with_slurm.py: {what}{': ' + detail if detail else ''}", file=sys.stderr)
        return 1

    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    try:
        # munge: its own key, socket, pid, log and seed files. munged runs as root here; where it refuses
        # root (an older munge, a stricter check), --force.
        mungekey = find("mungekey", SBIN)
        done = quiet([mungekey, "--create", "--keyfile", key]) if mungekey else None
        if done is None or done.returncode != 0:
            with open(os.open(key, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600), "wb") as f:
                f.write(os.urandom(1024))
        munged = [tools["munged"], f"--socket={sock}", f"--key-file={key}", f"--pid-file={munged_pid_file}",
                  f"--log-file={logs[0]}", f"--seed-file={os.path.join(munge_dir, 'munged.seed')}"]
        done = quiet(munged)
        if done.returncode != 0 and os.geteuid() == 0:
            print(f"with_slurm.py: munged refused ({done.stdout.strip()}): again with --force", flush=True)
            done = quiet(munged + ["--force"])
        if done.returncode != 0:
            return fail("could not start munged", done.stdout.strip())
        started.append(munged_pid_file)
        credential = quiet(["sh", "-c", f'"$0" -n -S "$1" | "$2" -S "$1"', tools["munge"], sock, tools["unmunge"]])
        if credential.returncode != 0:
            return fail("munged does not answer on its socket", credential.stdout.strip())

        host = socket.gethostname().split(".")[0]
        ctld_port, slurmd_port = free_ports(2)
        # The node as slurmd sees this machine (slurmd -C), so that it registers as configured.
        hardware = quiet([tools["slurmd"], "-C"]).stdout
        found = dict(re.findall(r"\b(CPUs|SocketsPerBoard|CoresPerSocket|ThreadsPerCore)=(\d+)", hardware))
        cpus = int(found.get("CPUs", 0)) or os.cpu_count() or 1
        layout = "".join(f" {field}={found[field]}" for field in ("SocketsPerBoard", "CoresPerSocket", "ThreadsPerCore")
                         if len(found) == 4)
        settings = f"""# Generated by tests/with_slurm.py: a throwaway one-node cluster in {folder}
ClusterName=bokehtest
SlurmctldHost={host}(127.0.0.1)
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
SlurmUser={user}
SlurmdUser={user}
AuthType=auth/munge
AuthInfo=socket={sock}
CredType=cred/munge
StateSaveLocation={os.path.join(folder, 'state')}
SlurmdSpoolDir={os.path.join(folder, 'spool')}
SlurmctldPidFile={ctld_pid_file}
SlurmdPidFile={slurmd_pid_file}
SlurmctldLogFile={logs[1]}
SlurmdLogFile={logs[2]}
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=2,bf_interval=1
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
KillWait=10
SlurmdParameters=config_overrides
NodeName={host} NodeAddr=127.0.0.1 CPUs={cpus}{layout} State=UNKNOWN
PartitionName=debug Nodes={host} Default=YES MaxTime=INFINITE State=UP
"""
        for d in ("state", "spool"):
            os.mkdir(os.path.join(folder, d), 0o755)
        with open(conf, "w") as f:
            f.write(settings)
        os.chmod(conf, 0o644)

        done = quiet([tools["slurmctld"], "-i"])
        if done.returncode != 0:
            return fail("could not start slurmctld", done.stdout.strip())
        started.append(ctld_pid_file)
        done = quiet([tools["slurmd"]])
        if done.returncode != 0:
            return fail("could not start slurmd", done.stdout.strip())
        started.append(slurmd_pid_file)
        end = time.monotonic() + START_TIMEOUT_S
        state = ""
        while time.monotonic() < end:
            done = quiet([tools["sinfo"], "--noheader", "--Node", "--format=%T"], timeout=10)
            state = done.stdout.strip()
            if done.returncode == 0 and state.startswith(("idle", "mixed", "allocated")):
                break
            time.sleep(0.3)
        else:
            return fail(f"the node did not come up within {START_TIMEOUT_S} s", f"sinfo says '{state}'")
        print(f"with_slurm.py: Slurm ({tools['slurmctld']}) one node '{host}' with {cpus} CPUs, as {user}, "
              f"SLURM_CONF={conf}", flush=True)
        return subprocess.call(argv, env=dict(env, BOKEH_TEST_SLURM_CONF=conf, BOKEH_TEST_SLURM_DIR=folder))
    finally:
        stop()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
