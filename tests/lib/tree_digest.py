#!/usr/bin/env python3
"""A folder's files as one line each, "PATH DEVICE:INODE:SIZE:MD5" (tests/readme_examples.sh).

    tree_digest.py DIR                 print the digest of every file under DIR (sorted)
    tree_digest.py BEFORE AFTER N      print "changed N PATH" for every file of BEFORE whose digest differs in
                                       AFTER (written over, or replaced by another file); new files are not changes
"""
import hashlib
import os
import sys


def digest(folder):
    lines = []
    for base, _, files in os.walk(folder):
        for name in files:
            path = os.path.join(base, name)
            st = os.lstat(path)
            h = hashlib.md5()
            if os.path.isfile(path):
                with open(path, "rb") as f:
                    for block in iter(lambda: f.read(1 << 20), b""):
                        h.update(block)
            lines.append("%s %d:%d:%d:%s" % (os.path.relpath(path, folder), st.st_dev, st.st_ino, st.st_size,
                                             h.hexdigest()))
    return "\n".join(sorted(lines))


def parse(text):
    return dict(line.rsplit(" ", 1) for line in text.split("\n") if line)


if len(sys.argv) == 2:
    print(digest(sys.argv[1]))
else:
    before, after = parse(sys.argv[1]), parse(sys.argv[2])
    for path, value in sorted(before.items()):
        if path in after and after[path] != value:
            print("changed %s %s" % (sys.argv[3], path))
