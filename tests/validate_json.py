#!/usr/bin/python3
"""Validate a bokehbench results file against its JSON schema (Debian's python3-jsonschema).

usage: validate_json.py SCHEMA_FILE RESULTS_JSON
Schemas refer to each other by file name ($ref: context.schema.json), resolved beside SCHEMA_FILE.
"""
import json
import pathlib
import sys

import jsonschema


def main(schema_path, results_path):
    schema_path = pathlib.Path(schema_path).resolve()
    schema = json.loads(schema_path.read_text())
    store = {p.name: json.loads(p.read_text()) for p in schema_path.parent.glob("*.schema.json")}
    resolver = jsonschema.RefResolver(base_uri=schema_path.parent.as_uri() + "/", referrer=schema, store=store)
    validator = jsonschema.Draft202012Validator(schema, resolver=resolver)
    results = json.loads(pathlib.Path(results_path).read_text())
    errors = sorted(validator.iter_errors(results), key=lambda e: list(e.path))
    for e in errors:
        print(f"{results_path}: {'/'.join(map(str, e.path)) or '(root)'}: {e.message}")
    if errors:
        sys.exit(1)
    print(f"{results_path}: valid against {schema_path.name}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
