#!/usr/bin/env python3
"""libkodawari.so exports exactly the functions kodawari.h declares, under the SONAME that
carries the major version: nothing of the engine or of the C++ standard library leaks out
(an application linking its own copy of either would otherwise bind to ours), and no
declared function is missing.

Usage: check_exports.py LIBKODAWARI.so KODAWARI.h SONAME
"""
import re
import subprocess
import sys


def main():
    library, header, soname = sys.argv[1:]
    symbols = subprocess.run(["nm", "-D", "--defined-only", library], check=True, capture_output=True, text=True).stdout
    exported = {line.split()[-1] for line in symbols.splitlines() if line.strip()}
    with open(header) as file:
        declared = set(re.findall(r"KODAWARI_C_API\s+[\w\s\*]*?\b(kodawari_\w+)\s*\(", file.read()))
    dynamic = subprocess.run(["readelf", "-d", library], check=True, capture_output=True, text=True).stdout
    found = re.search(r"Library soname: \[([^\]]+)\]", dynamic)
    problems = []
    if not declared:
        problems.append(f"no KODAWARI_C_API function found in {header}")
    problems += [f"exported but not declared in kodawari.h: {name}" for name in sorted(exported - declared)]
    problems += [f"declared in kodawari.h but not exported: {name}" for name in sorted(declared - exported)]
    if not found or found.group(1) != soname:
        problems.append(f"SONAME {found.group(1) if found else 'missing'}, expected {soname}")
    for problem in problems:
        print("check_exports:", problem)
    print(f"check_exports: {len(exported)} symbols exported, {len(declared)} declared, SONAME "
          f"{found.group(1) if found else '-'}, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
