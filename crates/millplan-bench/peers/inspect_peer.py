#!/usr/bin/env python3
"""The regex scan peer of `millplan inspect` for the benchmark table: every
GOTO of an APT file found by the one regular expression, as the issue that
set the goal defined it (no numbers converted).

Usage: inspect_peer.py FILE.apt
"""
import re
import sys

text = open(sys.argv[1]).read()
pts = re.findall(r"^GOTO/([-0-9.]+),([-0-9.]+),([-0-9.]+)", text, re.M)
print(f"{len(pts)} GOTOs, first {pts[0] if pts else None}, last {pts[-1] if pts else None}")
