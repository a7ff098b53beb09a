#!/usr/bin/env python3
"""Summarise ThreadSanitizer log files (scripts/sanitize.sh thread).

Each report is reduced to its kind and, for each stack it names (the warning's own, the two racing
accesses, a mutex's acquisitions, ...), the frame that made the access: the first outside the
sanitizer's runtime and the C library. A report in which no such frame is palp's own (a program or
test of this tree, or a libpalp* shared library; a library's header function inlined into palp's
binary is the library's) is counted as a library's and not printed: Debian's Cyclone DDS, CHOLMOD, its OpenMP
runtime and OpenBLAS are not instrumented, so TSan cannot see their atomics and takes their
internal hand-offs for races. Every other report is printed, and the exit status is 1 if there is
any.
A report of TSan's own end (ERROR: a deadly signal such as SEGV, FATAL, or CHECK failed) is a
finding whoever's frames it holds (since session 82): sanitize.sh runs with exitcode=0, which
also makes a crashed program exit 0, so this report is the only trace the crash leaves.
Usage: tsan_reports.py LOGFILE...
"""
import re
import sys

ACCESS = re.compile(r"^\s*(Write|Read|Previous write|Previous read|Atomic \w+|Previous atomic \w+)"
                    r"|^\s*Mutex M\d+ acquired|^\s*Cycle in lock order")
# "#N FUNCTION PLACE (MODULE+OFFSET)": a C++ function's demangled name has spaces in it (its
# parameters), so the place and the module are read from the end; until 2026-12-04 they were read
# from the front, which took a Fast DDS frame's parameter types for its place and blamed palp.
FRAME = re.compile(r"^\s*#\d+ (.+?) (\S+)(?: \((\S+)\))?\s*$")
RUNTIME = ("libtsan", "sanitizer_common", "libc.so", "libstdc++")


def accessor(frames):
    """The frame that made the access, (function, place, module, palp's?): the first outside the
    sanitizer and the C library. A library's header function inlined into palp's binary (its place
    under /usr/, as Cyclone's ddsi_serdata_to_ser) is the library's access; a stack TSan did not
    keep (its history ran out) blames no one."""
    for fn, where, module in frames:
        where, module = where or "", module or ""
        if any(r in where + module for r in RUNTIME):
            continue
        name = module.split("+")[0]
        ours = not where.startswith("/usr/") and (not re.match(r"lib.*\.so", name) or name.startswith("libpalp"))
        return fn, where, module, ours
    return ("?", "?", "", False)


def reports(text):
    for block in text.split("==================\n"):
        if "WARNING: ThreadSanitizer" in block:
            yield block


# TSan's own end: "==PID==ERROR: ThreadSanitizer: SEGV on unknown address ...", "FATAL:
# ThreadSanitizer: ...", "ThreadSanitizer: CHECK failed: ...". Such a report is not inside the
# "=================" lines of a warning, so it is looked for line by line in the whole log.
DEADLY = re.compile(r"(?:ERROR|FATAL): ThreadSanitizer\b|ThreadSanitizer: CHECK failed")


def deadly(text):
    """Each deadly report: its first line and the frames under it (up to TSan's ABORTING line, a
    warning's separator or 40 lines)."""
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if DEADLY.search(line):
            body = []
            for more in lines[i + 1:i + 41]:
                if DEADLY.search(more) or more.startswith("=================="):
                    break
                body.append(more)
                if "ABORTING" in more:
                    break
            yield re.sub(r"^==\d+==", "", line.strip()), body


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
            tops = [(head, accessor(fr)) for head, fr in stacks]
            if tops and not any(ours for _, (_, _, _, ours) in tops):
                lib += 1
                continue
            own.append((p, kind, tops))
    crashes = []
    for p in paths:
        for head, body in deadly(open(p, errors="replace").read()):
            crashes.append((p, head, body))
    for p, head, body in crashes:
        print(f"{p}: {head}")
        for line in body:
            if FRAME.match(line):
                print(f"    {line.strip()}")
    for p, kind, tops in own:
        print(f"{p}: {kind}")
        for head, (fn, where, module, _) in tops:
            print(f"    {head[:60]:60s} {fn} {where} {module}")
    print(f"tsan_reports: {len(crashes)} crash/fatal report(s), {len(own)} report(s) in palp's code, "
          f"{lib} inside uninstrumented libraries only (not shown)")
    return 1 if own or crashes else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
