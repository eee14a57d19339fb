#!/usr/bin/python3
"""The Kubernetes manifests in bench/cluster are complete and say what the README says they do.

usage: cluster_manifest_test.py CLUSTER_DIR

figure9-indexed-job.yaml: valid YAML; a PersistentVolumeClaim and an indexed Job (completions 3,
parallelism 3, completionMode Indexed) whose pods take the store's URL from the bokeh-store Secret and the
Job's uid as BOKEH_SWEEP_ID, and mount the claim. Its shell line is run for each index with a stand-in
bokehbench that records its arguments: every pod runs figure9 --shard auto/3 with --store "$BOKEH_STORE_URL",
each into a folder of its own. figure9-merge-job.yaml merges exactly those folders' files. No cluster is
needed (kubectl is not called). Exits 77 (skipped) without python3-yaml.
"""
import json
import os
import pathlib
import subprocess
import sys
import tempfile

try:
    import yaml
except ImportError:
    print("python3-yaml is not installed: skipped")
    sys.exit(77)


def main(cluster_dir):
    folder = pathlib.Path(cluster_dir)
    docs = list(yaml.safe_load_all((folder / "figure9-indexed-job.yaml").read_text()))
    kinds = [d["kind"] for d in docs]
    assert kinds == ["PersistentVolumeClaim", "Job"], kinds
    claim, job = docs
    assert job["apiVersion"] == "batch/v1", job["apiVersion"]
    spec = job["spec"]
    assert (spec["completions"], spec["parallelism"], spec["completionMode"]) == (3, 3, "Indexed"), spec
    pod = spec["template"]["spec"]
    assert pod["restartPolicy"] == "Never", pod["restartPolicy"]
    [container] = pod["containers"]
    env = {e["name"]: e["valueFrom"] for e in container["env"]}
    assert env["BOKEH_STORE_URL"] == {"secretKeyRef": {"name": "bokeh-store", "key": "url"}}, env
    assert env["BOKEH_SWEEP_ID"] == {"fieldRef": {"fieldPath": "metadata.labels['batch.kubernetes.io/controller-uid']"}}, env
    [volume] = pod["volumes"]
    assert volume["persistentVolumeClaim"]["claimName"] == claim["metadata"]["name"], volume
    assert container["volumeMounts"] == [{"name": volume["name"], "mountPath": "/results"}], container["volumeMounts"]
    assert container["command"] == ["sh", "-c"] and len(container["args"]) == 1, container

    # Each pod's command line, as its shell runs it (the Job sets JOB_COMPLETION_INDEX 0..2).
    out_dirs = []
    with tempfile.TemporaryDirectory() as tmp:
        stand_in = pathlib.Path(tmp) / "bokehbench"
        stand_in.write_text('#!/usr/bin/python3\nimport json, sys\nprint(json.dumps(sys.argv[1:]))\n')
        stand_in.chmod(0o755)
        for index in range(3):
            pod_env = dict(os.environ, PATH=f"{tmp}:{os.environ['PATH']}", JOB_COMPLETION_INDEX=str(index),
                           BOKEH_STORE_URL="postgresql://bench:secret word@db.example/bokeh", BOKEH_SWEEP_ID="uid")
            done = subprocess.run(["sh", "-c", container["args"][0]], env=pod_env, capture_output=True, text=True,
                                  check=True)
            argv = json.loads(done.stdout)
            assert argv[0] == "figure9", argv
            option = lambda name: argv[argv.index(name) + 1]
            assert option("--shard") == "auto/3", argv
            assert option("--store") == "postgresql://bench:secret word@db.example/bokeh", argv  # one word, quoted
            out_dirs.append(option("--out-dir"))
            print(f"JOB_COMPLETION_INDEX={index}: bokehbench {' '.join(argv)}")
    assert out_dirs == [f"/results/figure9/shard{i}" for i in (1, 2, 3)], out_dirs

    [merge] = list(yaml.safe_load_all((folder / "figure9-merge-job.yaml").read_text()))
    assert (merge["kind"], merge["apiVersion"]) == ("Job", "batch/v1"), merge
    merge_pod = merge["spec"]["template"]["spec"]
    [merger] = merge_pod["containers"]
    command = merger["command"]
    assert command[:2] == ["bokehbench", "merge"], command
    out = command.index("--out")
    assert command[2:out] == [f"{d}/figure9.json" for d in out_dirs], command
    assert command[out + 1] == "/results/figure9/figure9.json", command
    assert merge_pod["volumes"] == pod["volumes"], merge_pod["volumes"]
    assert merger["volumeMounts"] == container["volumeMounts"], merger["volumeMounts"]
    assert merger["image"] == container["image"], merger["image"]
    print("manifests: an indexed Job of 3 shards (auto/3) into one store, and a merge of its 3 files")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
