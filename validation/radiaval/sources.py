"""The hash of the Rust sources the radia Python package is built from, one implementation for
validation/setup (which stamps the venv with it after building the package) and for
radiaval.common.radia_package (which refuses a package built from other sources than the
checkout's: validating yesterday's renderer would pass silently).

    python validation/radiaval/sources.py [REPO_ROOT]     # prints the hash

No imports beyond the standard library: setup runs it before anything else is known to work.
"""
import hashlib
import os
import sys

SUFFIXES = (".rs", ".toml", ".lock", ".py", ".pyi")


def source_files(root):
    """crates/ (files ending in SUFFIXES) and the workspace's Cargo.toml and Cargo.lock, as
    paths relative to root, in byte order."""
    out = [p for p in ("Cargo.toml", "Cargo.lock") if os.path.isfile(os.path.join(root, p))]
    for d, dirs, files in os.walk(os.path.join(root, "crates")):
        dirs[:] = [x for x in dirs if x != "__pycache__"]
        for f in files:
            if f.endswith(SUFFIXES):
                out.append(os.path.relpath(os.path.join(d, f), root))
    return sorted(out, key=lambda p: p.encode())


def source_hash(root):
    """sha256 over (path, sha256 of content) of every source file."""
    h = hashlib.sha256()
    for rel in source_files(root):
        with open(os.path.join(root, rel), "rb") as f:
            digest = hashlib.sha256(f.read()).hexdigest()
        h.update(f"{digest}  {rel}\n".encode())
    return h.hexdigest()


if __name__ == "__main__":
    print(source_hash(sys.argv[1] if len(sys.argv) > 1 else
                      os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))))
