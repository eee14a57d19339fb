#!/usr/bin/env python3
"""Every function of the methods' libraries starts on a 64-byte boundary in the linked bokehbench.

Why it matters: CI's regression check times the baseline commit and the change as two builds. Without
-falign-functions=64 (CMakeLists.txt), a change to the harness alone moved where gaussian's CPU loops fell
within the CPU's 64-byte fetch windows and made that unchanged code 7-14% slower (README, "Regression
checks"). With every function aligned, an object file that did not change keeps its layout modulo 64.

  code_layout_test.py BOKEHBENCH METHOD_LIBRARY.a...
"""
import subprocess
import sys

ALIGN_BYTES = 64


def functions(path):
    """(name, section, address) of each function symbol objdump lists in path (an archive or a binary)."""
    out = subprocess.run(["objdump", "-t", "--wide", path], check=True, capture_output=True, text=True).stdout
    for line in out.splitlines():
        parts = line.split()
        # "<address> <flags...> F <section> <size> <name>"; flags take one to three columns.
        if len(parts) < 5 or "F" not in parts[1:-3]:
            continue
        f = parts.index("F", 1)
        yield parts[-1], parts[f + 1], int(parts[0], 16)


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    binary, libraries = sys.argv[1], sys.argv[2:]
    # Hot code only: the compiler places cold paths (.text.unlikely) unaligned, by design.
    hot, cold = set(), set()
    for lib in libraries:
        for name, section, _ in functions(lib):
            (cold if section.startswith(".text.unlikely") else hot).add(name)
    hot -= cold
    if not hot:
        sys.exit(f"no function symbols found in {libraries}")
    # A local function (an .isra clone, a static helper) has one copy per object file; the binary may
    # also hold copies of the same name from foreign static libraries (Debian's glslang, linked for
    # method packages), built without the alignment. So per name, only as many misaligned copies as
    # the binary has beyond the libraries' own count are others'.
    in_libraries = {}
    for lib in libraries:
        for name, section, _ in functions(lib):
            if name in hot and section.startswith(".text"):
                in_libraries[name] = in_libraries.get(name, 0) + 1
    copies = {}
    for name, section, address in functions(binary):
        if name in hot and section == ".text":
            copies.setdefault(name, []).append(address)
    checked, misaligned = 0, []
    for name, addresses in copies.items():
        checked += len(addresses)
        wrong = [a for a in addresses if a % ALIGN_BYTES]
        foreign = max(0, len(addresses) - in_libraries.get(name, len(addresses)))
        if len(wrong) > foreign:
            misaligned += [f"{a:#x} (+{a % ALIGN_BYTES}) {name}" for a in wrong]
    if checked == 0:
        sys.exit(f"none of the libraries' {len(hot)} functions were found in {binary}")
    print(f"{checked} functions of {len(libraries)} method libraries checked in {binary}")
    if misaligned:
        print(f"{len(misaligned)} do not start on a {ALIGN_BYTES}-byte boundary (is -falign-functions={ALIGN_BYTES} "
              f"in the compile options?):")
        print("\n".join(misaligned[:20]))
        sys.exit(1)


if __name__ == "__main__":
    main()
