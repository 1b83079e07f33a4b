#!/usr/bin/env python3
"""Reads an MCAP file Locus wrote (`--mcap`) with the `mcap` package and checks
it against Foxglove's published schemas.

Foxglove's JSON Schemas are taken from the npm package @foxglove/schemas 2.1.0
itself (fetched once into a cache directory and checked against its sha256),
not from Locus's copy, so the check is independent of the writer:

* every channel's schema of a `foxglove.*` name equals the package's;
* every message parses as JSON and validates against its schema (the
  package's for `foxglove.*`, the file's own for Locus's `locus.*` series).

Prints one JSON object: per topic, its schema name, schema and message
encodings and message count, and the number of messages that failed (with the
first few errors). Exits 1 if any message or schema fails.

    python3 scripts/foxglove_check.py OUT.mcap [--cache DIR]
"""

import argparse
import hashlib
import io
import json
import pathlib
import re
import sys
import tarfile
import urllib.request

import jsonschema
from mcap.reader import make_reader

TARBALL = "https://registry.npmjs.org/@foxglove/schemas/-/schemas-2.1.0.tgz"
SHA256 = "c6d2746e10bbb451a680307b6e5ec3b186de3263df2a41869a7757b3042fcbf0"


def published(cache: pathlib.Path) -> dict:
    """Foxglove's JSON Schemas by title, from the npm tarball."""
    path = cache / "foxglove-schemas-2.1.0.tgz"
    if not path.exists():
        cache.mkdir(parents=True, exist_ok=True)
        with urllib.request.urlopen(TARBALL, timeout=60) as r:
            data = r.read()
        tmp = path.with_suffix(".partial")
        tmp.write_bytes(data)
        tmp.rename(path)
    data = path.read_bytes()
    digest = hashlib.sha256(data).hexdigest()
    if digest != SHA256:
        sys.exit(f"{path}: sha256 {digest}, expected {SHA256}")
    with tarfile.open(fileobj=io.BytesIO(data)) as tar:
        src = tar.extractfile("package/dist/jsonschema/index.js").read().decode()
    blocks = re.findall(r"^exports\.(\w+) = (\{.*?^\});", src, re.S | re.M)
    schemas = {}
    for _, body in blocks:
        s = json.loads(body)
        schemas[s["title"]] = s
    return schemas


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mcap")
    ap.add_argument("--cache", default="target/foxglove-schemas")
    args = ap.parse_args()
    foxglove = published(pathlib.Path(args.cache))
    topics = {}
    validators = {}
    failed = False
    with open(args.mcap, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        for schema, channel, message in reader.iter_messages():
            t = topics.setdefault(
                channel.topic,
                {
                    "schema": schema.name,
                    "schema_encoding": schema.encoding,
                    "message_encoding": channel.message_encoding,
                    "count": 0,
                    "invalid": 0,
                    "errors": [],
                },
            )
            t["count"] += 1
            key = (schema.id, schema.name)
            if key not in validators:
                own = json.loads(schema.data)
                if schema.name.startswith("foxglove."):
                    if schema.name not in foxglove:
                        t["errors"].append(f"{schema.name} is not a published Foxglove schema")
                        failed = True
                        own = None
                    elif own != foxglove[schema.name]:
                        t["errors"].append(f"the file's {schema.name} differs from Foxglove's")
                        failed = True
                    reference = foxglove.get(schema.name, own)
                else:
                    reference = own
                cls = jsonschema.validators.validator_for(reference)
                cls.check_schema(reference)
                validators[key] = cls(reference)
            try:
                value = json.loads(message.data)
                errors = [e.message for e in validators[key].iter_errors(value)]
            except ValueError as e:
                errors = [f"not JSON: {e}"]
            if errors:
                failed = True
                t["invalid"] += 1
                if len(t["errors"]) < 3:
                    t["errors"].append(f"message {message.sequence}: {errors[0]}")
    out = {
        "summary_message_count": summary.statistics.message_count
        if summary and summary.statistics
        else None,
        "topics": topics,
    }
    print(json.dumps(out, indent=1, sort_keys=True))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
