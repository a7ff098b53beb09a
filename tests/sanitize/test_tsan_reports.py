#!/usr/bin/env python3
"""tsan_reports.py (scripts/sanitize.sh thread's verdict) on small logs of known content.

The logs below are copied from real ThreadSanitizer output (gcc 12, bookworm; the SEGV from a
probe that writes through NULL in a thread, run with sanitize.sh's TSAN_OPTIONS, exit status 0),
with paths shortened. Each case states the exit status and the count it must print; none is
computed by tsan_reports.py itself.
Usage: test_tsan_reports.py PATH/TO/tsan_reports.py
"""
import os
import subprocess
import sys
import tempfile

SEP = "==================\n"

LIB_RACE = SEP + """WARNING: ThreadSanitizer: data race (pid=100)
  Write of size 8 at 0x7b0400000010 by thread T2:
    #0 ddsrt_free <null> (libddsc.so.0+0x8a1b0)
    #1 dds_stream_free_sample <null> (libddsc.so.0+0x6c2f1)

  Previous read of size 8 at 0x7b0400000010 by thread T1:
    #0 ddsi_serdata_to_ser /usr/include/dds/ddsi/ddsi_serdata.h:210 (palp-server+0x4a1c2)

SUMMARY: ThreadSanitizer: data race (/usr/lib/x86_64-linux-gnu/libddsc.so.0+0x8a1b0) in ddsrt_free
""" + SEP

PALP_RACE = SEP + """WARNING: ThreadSanitizer: data race (pid=6908)
  Read of size 4 at 0x55c5907fd064 by main thread:
    #0 main /tmp/probe/segv2.c:6 (segv2+0x12b2)

  Previous write of size 4 at 0x55c5907fd064 by thread T1:
    #0 run /tmp/probe/segv2.c:5 (segv2+0x1208)

SUMMARY: ThreadSanitizer: data race /tmp/probe/segv2.c:6 in main
""" + SEP

# A crash: not between separator lines, and its only frame outside the runtime a library's (a
# crash inside a library that palp called with a bad pointer is still a finding).
SEGV = """==6614==ERROR: ThreadSanitizer: SEGV on unknown address 0x000000000000 (pc 0x56106a64a21e bp 0x7fbfa693e110 sp 0x7fbfa693e0e0 T6620)
==6614==The signal is caused by a WRITE memory access.
==6614==Hint: address points to the zero page.
    #0 dds_write <null> (libddsc.so.0+0x4121e)
    #1 __tsan_thread_start_func ../../../../src/libsanitizer/tsan/tsan_interceptors_posix.cpp:991 (libtsan.so.2+0x3898f)
    #2 start_thread nptl/pthread_create.c:442 (libc.so.6+0x891f4)

ThreadSanitizer can not provide additional info.
SUMMARY: ThreadSanitizer: SEGV (libddsc.so.0+0x4121e) in dds_write
==6614==ABORTINGThreadSanitizer:DEADLYSIGNAL
"""

FATAL = "==7001==FATAL: ThreadSanitizer: unexpected memory mapping 0x7f0000000000-0x7f0000100000\n"
CHECK = ("==7002==ThreadSanitizer: CHECK failed: tsan_rtl.cpp:123 \"((x)) != (0)\" (0x0, 0x0) (tid=7002)\n"
         "    #0 __tsan::CheckUnwind() ../../../../src/libsanitizer/tsan/tsan_rtl.cpp:627 (libtsan.so.2+0x99c2b)\n")


def run(script, logs):
    with tempfile.TemporaryDirectory() as d:
        paths = []
        for i, text in enumerate(logs):
            p = os.path.join(d, f"tsan.{1000 + i}")
            with open(p, "w") as f:
                f.write(text)
            paths.append(p)
        r = subprocess.run([sys.executable, script] + paths, capture_output=True, text=True, timeout=60)
        return r.returncode, r.stdout


def main(script):
    cases = [
        # (name, logs, exit status, text the summary line must hold)
        ("library race only", [LIB_RACE], 0, "0 crash/fatal report(s), 0 report(s) in palp's code, 1 inside"),
        ("palp's race", [PALP_RACE], 1, "0 crash/fatal report(s), 1 report(s) in palp's code, 0 inside"),
        ("SEGV in a library's frame", [SEGV], 1, "1 crash/fatal report(s), 0 report(s) in palp's code"),
        ("SEGV after a library race", [LIB_RACE + SEGV], 1, "1 crash/fatal report(s), 0 report(s) in palp's code, 1 inside"),
        ("FATAL", [LIB_RACE, FATAL], 1, "1 crash/fatal report(s)"),
        ("CHECK failed", [CHECK], 1, "1 crash/fatal report(s)"),
    ]
    fail = 0
    for name, logs, want, summary in cases:
        rc, out = run(script, logs)
        last = out.strip().splitlines()[-1] if out.strip() else ""
        ok = rc == want and summary in last
        if want == 1 and "crash/fatal report(s)" in summary and not summary.startswith("0 "):
            # the crash is named, with its first line, so that the log can be found
            ok = ok and ("SEGV" in out or "FATAL" in out or "CHECK failed" in out)
        print(f"{'ok ' if ok else 'BAD'} {name}: exit {rc} (want {want}); {last}")
        fail |= not ok
    return 1 if fail else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
