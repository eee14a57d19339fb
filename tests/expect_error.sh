#!/bin/sh
# usage: expect_error.sh PATTERN COMMAND...  Passes when COMMAND exits non-zero (not by a signal)
# and its output contains PATTERN.
pattern=$1; shift
out=$("$@" 2>&1); rc=$?
printf '%s\n' "$out"
if [ "$rc" -eq 0 ]; then echo "expected a non-zero exit"; exit 1; fi
if [ "$rc" -gt 128 ]; then echo "crashed with signal $((rc - 128))"; exit 1; fi
case "$out" in *"$pattern"*) exit 0 ;; esac
echo "expected the message to contain: $pattern"; exit 1
