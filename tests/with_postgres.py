#!/usr/bin/python3
"""Runs a command beside a throwaway PostgreSQL server (Debian's postgresql-15), then stops it.

usage: with_postgres.py COMMAND [ARGS...]

initdb in a temporary folder, the server listening only on a unix socket in that folder (no TCP), run
as a non-root user (PostgreSQL refuses root: as root, `runuser -u nobody`). The command gets
BOKEH_TEST_POSTGRES_HOST (the socket folder) and BOKEH_TEST_POSTGRES_USER; its exit status is this
script's. The server is stopped and the folder removed at the end, whether the command passed, failed
or was interrupted. With no PostgreSQL installed, the command runs without the variables (its
PostgreSQL tests then skip, saying why) and this says so.
"""
import glob
import os
import pwd
import shutil
import signal
import subprocess
import sys
import tempfile


def find_bin():
    for d in sorted(glob.glob("/usr/lib/postgresql/*/bin"), reverse=True):
        if os.path.exists(os.path.join(d, "initdb")) and os.path.exists(os.path.join(d, "pg_ctl")):
            return d
    return None


def main(argv):
    if not argv:
        sys.exit(__doc__)
    bindir = find_bin()
    if bindir is None:
        print("with_postgres.py: no PostgreSQL server installed (apt-get install postgresql): running without it",
              flush=True)
        return subprocess.call(argv)
    root = os.geteuid() == 0
    user = "nobody" if root else pwd.getpwuid(os.geteuid()).pw_name
    folder = tempfile.mkdtemp(prefix="bokeh_pg_")
    data = os.path.join(folder, "data")
    as_user = (["runuser", "-u", user, "--"] if root else [])
    if root:
        os.chown(folder, pwd.getpwnam(user).pw_uid, pwd.getpwnam(user).pw_gid)
    os.chmod(folder, 0o755)
    started = False
    def stop(*_):
        if started:
            subprocess.call(as_user + [os.path.join(bindir, "pg_ctl"), "-D", data, "-m", "immediate", "-w", "stop"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        shutil.rmtree(folder, ignore_errors=True)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    try:
        subprocess.run(as_user + [os.path.join(bindir, "initdb"), "-D", data, "-U", user, "--auth=trust", "-E", "UTF8",
                                  "--no-sync"], check=True, stdout=subprocess.DEVNULL)
        options = f"-k {folder} -c listen_addresses='' -c fsync=off -c max_connections=50"
        subprocess.run(as_user + [os.path.join(bindir, "pg_ctl"), "-D", data, "-o", options, "-l",
                                  os.path.join(folder, "log"), "-w", "-t", "60", "start"], check=True,
                       stdout=subprocess.DEVNULL)
        started = True
        print(f"with_postgres.py: PostgreSQL ({bindir}) on socket {folder} as {user}", flush=True)
        env = dict(os.environ, BOKEH_TEST_POSTGRES_HOST=folder, BOKEH_TEST_POSTGRES_USER=user)
        return subprocess.call(argv, env=env)
    except subprocess.CalledProcessError as e:
        log = os.path.join(folder, "log")
        if os.path.exists(log):
            print(open(log).read(), file=sys.stderr)
        print(f"with_postgres.py: could not start PostgreSQL: {e}", file=sys.stderr)
        return 1
    finally:
        stop()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
