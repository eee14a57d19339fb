#!/usr/bin/python3
"""Where a lavapipe shader spends its time, instruction by instruction.

lavapipe JIT-compiles each shader into anonymous memory, so perf sees addresses without symbols. This runs a
command (a long frame: `bokehbench render` at 3840x2160, say), samples it with `perf record` while its shader runs,
copies the anonymous executable mappings (the JIT code) out of the live process with gdb, disassembles the one the
samples fell in with objdump and prints the share of samples by block of code and the hottest instructions. A
sample lands on the instruction after a slow one (a load that missed, a sqrt). Needs perf (perf_event_paranoid <= 2) and gdb; a tool
for people tuning shaders, not part of the tests. results/README.md ("Clearing the fused pass's bins once") shows
what it found.

  python3 bench/jit_profile.py --delay 1.0 --seconds 1.0 -- \\
      build/bokehbench render --resolutions 3840x2160 -N 81 -k 2 --precision f16 --fit-max-coc 80 --out /tmp/x.exr
"""
import argparse
import collections
import os
import shutil
import subprocess
import sys
import tempfile
import time


def anonymous_code(pid):
    """The process's anonymous executable mappings (lavapipe's JIT code among them), as (start, end)."""
    regions = []
    with open(f"/proc/{pid}/maps") as maps:
        for line in maps:
            fields = line.split()
            if len(fields) == 5 and fields[1] == "r-xp":  # no path: anonymous
                regions.append(tuple(int(x, 16) for x in fields[0].split("-")))
    return regions


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--delay", type=float, default=1.0, help="seconds from the start to the first sample "
                        "(past the shader compiles)")
    parser.add_argument("--seconds", type=float, default=1.0, help="seconds to sample")
    parser.add_argument("--block-bytes", type=int, default=512, help="code block size for the shares")
    parser.add_argument("--top", type=int, default=20, help="hottest instructions to list")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="-- then the command to profile")
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("no command to profile (give it after --)")
    for tool in ("perf", "gdb", "objdump"):
        if shutil.which(tool) is None:
            sys.exit(f"jit_profile: error: {tool} is not installed (apt-get install linux-perf gdb binutils)")

    work = tempfile.mkdtemp(prefix="jit_profile.")
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(args.delay)
    if proc.poll() is not None:
        sys.exit(f"jit_profile: error: the command ended (exit {proc.returncode}) before {args.delay} s: "
                 "a longer frame or a shorter --delay")
    samples_file = os.path.join(work, "perf.data")
    subprocess.run(["perf", "record", "-q", "-F", "4000", "-p", str(proc.pid), "-o", samples_file, "--",
                    "sleep", str(args.seconds)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    regions = anonymous_code(proc.pid) if proc.poll() is None else []
    if not regions:
        proc.wait()
        sys.exit("jit_profile: error: the command ended while sampling, before its JIT code could be copied: "
                 "a longer frame or shorter --delay / --seconds")
    # Every anonymous code mapping is copied while the process lives; the one the samples fell in is read.
    dumps = [f"dump memory {os.path.join(work, f'code{i}.bin')} {a:#x} {b:#x}" for i, (a, b) in enumerate(regions)]
    subprocess.run(["gdb", "-p", str(proc.pid), "-batch"] + [x for d in dumps for x in ("-ex", d)],
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    proc.wait()

    script = subprocess.run(["perf", "script", "-i", samples_file, "-F", "ip"], capture_output=True, text=True,
                            check=True).stdout
    ips = [int(x, 16) for x in script.split()]
    hits = [sum(a <= ip < b for ip in ips) for a, b in regions]
    index = max(range(len(regions)), key=lambda i: hits[i])
    region, code_file = regions[index], os.path.join(work, f"code{index}.bin")
    listing = subprocess.run(["objdump", "-D", "-b", "binary", "-m", "i386:x86-64", f"--adjust-vma={region[0]:#x}",
                              code_file], capture_output=True, text=True, check=True).stdout
    text = {}
    for line in listing.splitlines():
        head, _, rest = line.partition(":")
        if "\t" in rest:
            try:
                text[int(head, 16) - region[0]] = rest.split("\t")[-1]
            except ValueError:
                pass
    offsets = [ip - region[0] for ip in ips if region[0] <= ip < region[1]]
    total = len(ips)
    if not offsets:
        sys.exit(f"jit_profile: error: none of {total} samples fell in the JIT code")
    print(f"{total} samples, {100 * len(offsets) / total:.1f}% in the JIT code "
          f"({region[1] - region[0]} bytes; offsets below are from its start; code kept in {work})")
    blocks = collections.Counter(o // args.block_bytes * args.block_bytes for o in offsets)
    print(f"\nshare by {args.block_bytes}-byte block (blocks of 0.5% or more):")
    for block, count in sorted(blocks.items()):
        if count >= 0.005 * total:
            print(f"  {block:#07x}  {100 * count / total:5.1f}%")
    print(f"\nhottest instructions (a sample lands on the one after a slow instruction):")
    for offset, count in collections.Counter(offsets).most_common(args.top):
        print(f"  {offset:#07x}  {100 * count / total:5.1f}%  {text.get(offset, '?')}")


if __name__ == "__main__":
    main()
