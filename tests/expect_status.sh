#!/bin/sh
# usage: expect_status.sh STATUS PATTERN COMMAND...  Passes when COMMAND exits with exactly STATUS
# and its output contains PATTERN (for commands whose exit status is a verdict, e.g. compare).
status=$1; pattern=$2; shift 2
out=$("$@" 2>&1); rc=$?
printf '%s\n' "$out"
if [ "$rc" -ne "$status" ]; then echo "expected exit status $status, got $rc"; exit 1; fi
case "$out" in *"$pattern"*) exit 0 ;; esac
echo "expected the output to contain: $pattern"; exit 1
