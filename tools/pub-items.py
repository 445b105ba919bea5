#!/usr/bin/env python3
"""Count aacmm-core's public surface: what a user of the crate can name.

    python3 tools/pub-items.py            # builds the rustdoc JSON, then counts
    python3 tools/pub-items.py --json F   # counts an existing rustdoc JSON file

The count walks rustdoc's JSON (nightly: `--output-format json`, with
`--document-hidden-items` so that `#[doc(hidden)]` cannot hide anything)
from the crate root, following public modules, public re-exports (`pub use`)
of items defined in this crate, and each public type's inherent impls.
Each item is counted once however many paths reach it.

- **items**: modules, structs, enums, unions, traits, functions (free
  functions, inherent methods and the methods a public trait declares),
  constants, statics, type aliases, macros and associated constants/types
  of inherent impls and public traits. Not counted: members of trait impls
  (`impl Display for X { fn fmt }` adds nothing a user names), derived
  impls, and enum variants (listed separately: they carry no `pub`).
- **fields**: `pub` fields of public structs (named and tuple).
- **variants** and **variant fields**: the variants of public enums and
  their fields, reported beside the two counts, not in them.

The rustdoc JSON build needs a nightly toolchain (`rustup toolchain install
nightly`); it goes to its own target directory (target/pub-items) so that it
never invalidates the stable build.
"""

import argparse
import collections
import json
import os
import subprocess
import sys

ITEM_KINDS = {
    "module",
    "struct",
    "enum",
    "union",
    "trait",
    "function",
    "constant",
    "static",
    "type_alias",
    "macro",
    "proc_macro",
    "assoc_const",
    "assoc_type",
    "trait_alias",
}


def build(root):
    target = os.path.join(root, "target", "pub-items")
    cmd = [
        "cargo", "+nightly", "rustdoc", "-p", "aacmm-core", "--lib", "--quiet", "--",
        "-Z", "unstable-options", "--output-format", "json", "--document-hidden-items",
    ]
    env = dict(os.environ, CARGO_TARGET_DIR=target)
    subprocess.run(cmd, cwd=root, env=env, check=True)
    return os.path.join(target, "doc", "aacmm_core.json")


def kind(item):
    return next(iter(item["inner"]))


class Walk:
    def __init__(self, doc):
        self.index = doc["index"]
        self.seen = set()
        self.counts = collections.Counter()
        self.by_module = collections.Counter()

    def get(self, id_):
        item = self.index.get(str(id_))
        if item is None or item["crate_id"] != 0:
            return None
        return item

    def module_of(self, item):
        span = item.get("span") or {}
        return span.get("filename", "?")

    def count(self, item, what):
        self.counts[what] += 1
        if what in ("items", "fields"):
            self.by_module[self.module_of(item)] += 1

    def visit(self, id_):
        item = self.get(id_)
        if item is None or item["id"] in self.seen:
            return
        self.seen.add(item["id"])
        k = kind(item)
        inner = item["inner"][k]
        if k == "use":
            # A re-export: the target is what is public, counted once.
            if inner.get("id") is not None:
                target = self.get(inner["id"])
                if target is not None and kind(target) == "module" and inner.get("is_glob"):
                    for child in target["inner"]["module"]["items"]:
                        self.visit(child)
                else:
                    self.visit(inner["id"])
            return
        if k in ITEM_KINDS:
            self.count(item, "items")
        if k == "module":
            for child in inner["items"]:
                self.visit(child)
        elif k in ("struct", "union"):
            fields = []
            if k == "union":
                fields = inner.get("fields", [])
            else:
                shape = inner["kind"]
                if isinstance(shape, dict):
                    body = shape.get("plain") or {}
                    fields = body.get("fields", []) if "plain" in shape else shape.get("tuple", [])
            for f in fields:
                field = self.get(f) if f is not None else None
                if field is not None and field["visibility"] == "public":
                    self.count(field, "fields")
            self.impls(inner["impls"])
        elif k == "enum":
            for v in inner["variants"]:
                variant = self.get(v)
                if variant is None:
                    continue
                self.count(variant, "variants")
                shape = variant["inner"]["variant"]["kind"]
                if isinstance(shape, dict):
                    body = shape.get("struct") or {}
                    fields = body.get("fields", []) if "struct" in shape else shape.get("tuple", [])
                    self.counts["variant fields"] += sum(1 for f in fields if f is not None)
            self.impls(inner["impls"])
        elif k == "trait":
            for member in inner["items"]:
                self.visit(member)

    def impls(self, ids):
        for i in ids:
            impl = self.get(i)
            if impl is None:
                continue
            body = impl["inner"]["impl"]
            # Trait impls (and the blanket/auto ones rustdoc synthesises)
            # add no names of their own.
            if body.get("trait") is not None or body.get("is_synthetic") or body.get("blanket_impl"):
                continue
            for member in body["items"]:
                m = self.get(member)
                if m is not None and m["visibility"] == "public":
                    self.visit(member)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--json", help="an existing rustdoc JSON file of aacmm-core")
    parser.add_argument("--by-file", action="store_true", help="items + fields per source file")
    args = parser.parse_args()
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    path = args.json or build(root)
    with open(path) as f:
        doc = json.load(f)
    walk = Walk(doc)
    walk.visit(doc["root"])
    c = walk.counts
    print(f"pub items {c['items']}, pub fields {c['fields']}, total {c['items'] + c['fields']}"
          f" (variants {c['variants']}, variant fields {c['variant fields']})")
    if args.by_file:
        for name, n in sorted(walk.by_module.items(), key=lambda kv: -kv[1]):
            print(f"{n:6} {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
