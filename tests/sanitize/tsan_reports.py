#!/usr/bin/env python3
"""Summarise ThreadSanitizer log files (scripts/sanitize.sh thread).

Each report is reduced to its kind and, for each stack it names (the two racing accesses, a
mutex's acquisitions, ...), the first frame outside the sanitizer's runtime and the C library. A
report in which no such frame is palp's own (a program or test of this tree, or a libpalp* shared
library) is counted as a library's and not printed: Debian's Cyclone DDS, CHOLMOD, its OpenMP
runtime and OpenBLAS are not instrumented, so TSan cannot see their atomics and takes their
internal hand-offs for races. Every other report is printed, and the exit status is 1 if there is
any.
Usage: tsan_reports.py LOGFILE...
"""
import re
import sys

ACCESS = re.compile(r"^\s*(Write|Read|Previous write|Previous read|Atomic \w+|Previous atomic \w+)"
                    r"|^\s*Mutex M\d+ acquired|^\s*Cycle in lock order")
FRAME = re.compile(r"^\s*#\d+ (\S+) (\S+)(?: \((\S+)\))?")
RUNTIME = ("libtsan", "sanitizer_common", "libc.so", "libstdc++")


def palp_frame(module):
    """A frame in palp's own code: its programs and tests, or its shared libraries (libpalp*)."""
    name = module.split("+")[0]
    if not name or name.startswith("("):
        return False  # no stack kept (TSan's history ran out): nothing to blame
    return not re.match(r"lib.*\.so", name) or name.startswith("libpalp")


def first_own(frames):
    """The frame that made the access: the first outside the sanitizer and the C library, as
    (function, place, module). A library's header function inlined into palp's binary (its place
    under /usr/, as Cyclone's ddsi_serdata_to_ser) is the library's access, not palp's."""
    for fn, where, module in frames:
        if any(r in (where or "") + (module or "") for r in RUNTIME):
            continue
        if (where or "").startswith("/usr/"):
            return fn, where, "(inlined library header)"
        return fn, where, module or ""
    return ("?", "?", "")


def reports(text):
    for block in text.split("==================\n"):
        if "WARNING: ThreadSanitizer" in block:
            yield block


def main(paths):
    own, lib = [], 0
    for p in paths:
        for rep in reports(open(p, errors="replace").read()):
            kind = re.search(r"WARNING: ThreadSanitizer: ([^(\n]+)", rep).group(1).strip()
            stacks, cur = [], None
            for line in rep.splitlines():
                if "WARNING: ThreadSanitizer" in line:
                    cur = []  # the stack right under the warning (an unlock, a signal handler)
                    stacks.append((kind, cur))
                elif ACCESS.match(line):
                    cur = []
                    stacks.append((line.strip(), cur))
                elif cur is not None:
                    m = FRAME.match(line)
                    if m:
                        cur.append(m.groups())
                    elif not line.strip():
                        cur = None
            tops = [(head, first_own(fr)) for head, fr in stacks]
            if tops and not any(palp_frame(module) for _, (_, _, module) in tops):
                lib += 1
                continue
            own.append((p, kind, tops))
    for p, kind, tops in own:
        print(f"{p}: {kind}")
        for head, (fn, where, module) in tops:
            print(f"    {head[:60]:60s} {fn} {where} {module}")
    print(f"tsan_reports: {len(own)} report(s) in palp's code, {lib} inside uninstrumented libraries only (not shown)")
    return 1 if own else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
