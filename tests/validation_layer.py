#!/usr/bin/python3
"""Run a command under the Khronos validation layer; fail on any message not documented.

usage: validation_layer.py ALLOWLIST COMMAND...

The layer (Debian's vulkan-validationlayers) runs its core checks plus synchronization and
best-practices validation, logging every message to a file. The command must pass, the loader must
show that the layer was really inserted, and every message ID must be listed in ALLOWLIST (one
"ID  # why it is acceptable" per line); anything else fails the test with the messages printed.
"""
import collections
import os
import pathlib
import re
import subprocess
import sys
import tempfile

MANIFEST = pathlib.Path("/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json")


def allowed_ids(path):
    ids = {}
    for line in pathlib.Path(path).read_text().splitlines():
        entry = line.split("#", 1)
        if entry[0].strip():
            ids[entry[0].strip()] = entry[1].strip() if len(entry) > 1 else ""
    return ids


def main(allowlist, command):
    if not MANIFEST.exists():
        sys.exit(f"the Khronos validation layer is not installed ({MANIFEST}): apt-get install vulkan-validationlayers "
                 "(.ci/setup does)")
    allowed = allowed_ids(allowlist)
    with tempfile.TemporaryDirectory() as tmp:
        log = pathlib.Path(tmp) / "validation.log"
        pathlib.Path(tmp, "vk_layer_settings.txt").write_text(
            "khronos_validation.debug_action = VK_DBG_LAYER_ACTION_LOG_MSG\n"
            f"khronos_validation.log_filename = {log}\n"
            "khronos_validation.report_flags = error,warn,perf\n"
            "khronos_validation.duplicate_message_limit = 3\n"
            "khronos_validation.enables = VK_VALIDATION_FEATURE_ENABLE_BEST_PRACTICES_EXT,"
            "VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT\n")
        env = dict(os.environ, VK_INSTANCE_LAYERS="VK_LAYER_KHRONOS_validation", VK_LAYER_SETTINGS_PATH=tmp,
                   VK_LOADER_DEBUG="layer")
        run = subprocess.run(command, env=env, capture_output=True, text=True)
        output = run.stdout + run.stderr
        text = log.read_text() if log.exists() else ""
    loader_lines = [l for l in output.splitlines() if "VK_LAYER_KHRONOS_validation" in l]
    if not any("Insert" in l or "insert" in l for l in loader_lines):
        print(output[-4000:])
        sys.exit("the loader did not report inserting VK_LAYER_KHRONOS_validation: nothing was validated")
    # Each message starts unindented, "ID(SEVERITY / TYPE): msgNum: N - text", with indented lines after.
    messages = re.split(r"\n(?=\S+\([A-Z]+ / [A-Z]+\): msgNum:)", text.strip()) if text.strip() else []
    counts = collections.Counter()
    undocumented = []
    for m in messages:
        found = re.match(r"(\S+)\([A-Z]+ / [A-Z]+\): msgNum:", m)
        message_id = found.group(1) if found else m.splitlines()[0]
        counts[message_id] += 1
        if message_id not in allowed:
            undocumented.append(m.strip())
    for message_id, n in sorted(counts.items()):
        print(f"{n:5d}  {message_id}  ({'documented: ' + allowed[message_id] if message_id in allowed else 'UNDOCUMENTED'})")
    if run.returncode != 0:
        print("\n".join(l for l in output.splitlines() if "loader" not in l.lower())[-6000:])
        sys.exit(f"the command failed under the validation layer (exit {run.returncode})")
    if undocumented:
        print("\n\n".join(undocumented[:20]))
        sys.exit(f"{len(undocumented)} validation messages not documented in {allowlist}")
    print("\n".join(l for l in output.splitlines() if "loader" not in l.lower()))
    print(f"validation layer (core, synchronization, best practices): {len(messages)} messages, all documented")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
