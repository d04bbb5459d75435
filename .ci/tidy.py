#!/usr/bin/env python3
"""clang-tidy on the production translation units of a build, with its clean results cached.

A unit's key is a hash of everything its result depends on: clang-tidy's version, .clang-tidy,
the unit's compile command (this checkout's and build's paths taken out) and the contents of the
source and of every header it includes (the list ninja recorded when it compiled the unit:
`ninja -t deps`). A unit whose key is in the cache was clean with exactly these inputs and is not
checked again; a unit without a recorded list (not compiled yet) is always checked. Only clean
results are kept, so a warning is reported on every run until it is fixed.

Usage: tidy.py BUILD_DIR JOBS REGEX
  REGEX: the units to check, matched against their paths relative to the repository root.
The cache: $STAC_TIDY_CACHE, else ${XDG_CACHE_HOME:-~/.cache}/stac-clang-tidy (one empty file per
clean key; deleting the folder costs one full run).
"""
import concurrent.futures
import hashlib
import json
import os
import re
import subprocess
import sys


def ninja_deps(build):
    """{object path relative to build: [dependency paths]} from ninja's deps log."""
    out = subprocess.run(["ninja", "-C", build, "-t", "deps"], capture_output=True, text=True,
                         check=True).stdout
    deps, current = {}, None
    for line in out.splitlines():
        if not line.strip():
            current = None
        elif not line.startswith(" "):
            # "obj.o: #deps 12, deps mtime 123 (VALID)"; STALE entries are not trusted
            target, _, rest = line.partition(": #deps")
            current = target if "(VALID)" in rest else None
            if current is not None:
                deps[current] = []
        elif current is not None:
            deps[current].append(line.strip())
    return deps


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    build, jobs, pattern = sys.argv[1], int(sys.argv[2]), re.compile(sys.argv[3])
    root = os.getcwd()
    build_abs = os.path.abspath(build)
    cache = os.environ.get("STAC_TIDY_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "stac-clang-tidy")
    os.makedirs(cache, exist_ok=True)

    version = subprocess.run(["clang-tidy", "--version"], capture_output=True, text=True,
                             check=True).stdout
    with open(os.path.join(root, ".clang-tidy"), "rb") as f:
        config = f.read()
    with open(os.path.join(build, "compile_commands.json")) as f:
        commands = json.load(f)
    deps = ninja_deps(build)

    file_hashes = {}

    def content_hash(path):
        if path not in file_hashes:
            try:
                with open(path, "rb") as f:
                    file_hashes[path] = hashlib.sha256(f.read()).hexdigest()
            except OSError:
                file_hashes[path] = "missing"
        return file_hashes[path]

    def portable(text):  # this checkout's and this build's paths out of a command or a path
        return text.replace(build_abs, "<build>").replace(root, "<root>")

    units, seen = [], set()
    for entry in commands:
        source = entry["file"]
        relative = os.path.relpath(source, root)
        if source in seen or not pattern.match(relative):
            continue
        seen.add(source)
        # The object: the entry's "output" (CMake 3.20+ with some generators), else the command's
        # -o (CMake 3.25's Ninja generator writes no "output").
        output = entry.get("output")
        if output is None:
            m = re.search(r"(?:^|\s)-o\s+(\S+)", entry["command"])
            output = m.group(1) if m else None
        listed = None
        if output is not None:
            output = os.path.normpath(os.path.join(entry["directory"], output))
            listed = deps.get(os.path.relpath(output, build_abs))
        key = None
        if listed:
            h = hashlib.sha256()
            for part in (version.encode(), config, portable(entry["command"]).encode()):
                h.update(part)
                h.update(b"\0")
            for dep in sorted(set(listed) | {source}):
                path = os.path.normpath(os.path.join(build_abs, dep))
                h.update(f"{portable(path)}={content_hash(path)}\n".encode())
            key = h.hexdigest()
        units.append((relative, source, key))

    to_check = [u for u in units if u[2] is None or not os.path.exists(os.path.join(cache, u[2]))]
    print(f"check-style: clang-tidy on {len(units)} translation units: "
          f"{len(units) - len(to_check)} clean before with the same inputs (cached), "
          f"{len(to_check)} to check ({jobs} at a time)", flush=True)

    def check(unit):
        relative, source, key = unit
        run = subprocess.run(["clang-tidy", "-p", build, "--quiet", "--warnings-as-errors=*", source],
                             capture_output=True, text=True)
        if run.returncode == 0 and key is not None:
            open(os.path.join(cache, key), "wb").close()
        return relative, run.returncode, run.stdout + run.stderr

    failed = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        for relative, code, output in pool.map(check, to_check):
            if code != 0:
                failed.append(relative)
                lines = [l for l in output.splitlines() if "warning:" in l or "error:" in l]
                sys.stderr.write("\n".join(sorted(set(lines)) or [output]) + "\n")
    if failed:
        sys.stderr.write(f"check-style: clang-tidy found the problems above in {len(failed)} "
                         f"units: {', '.join(failed)}\n")
        sys.exit(1)
    print("check-style: clean")


if __name__ == "__main__":
    main()
