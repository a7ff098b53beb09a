#!/usr/bin/env python3
"""The wire contract grows only by adding (idl/palp_types.idl's header; docs/robustness.md).

Usage: idl_baseline.py IDL BASELINE          compare (the test interop_idl_baseline)
       idl_baseline.py IDL BASELINE --write  write BASELINE from IDL (a deliberate change of the contract)

Every type is @final, plain XCDR1: a member inserted, removed, retyped or rebounded shifts every later
field for a peer built on the older IDL, silently; a renamed member or type breaks the source of a
third-party station built with fastddsgen's accessors. Session 83's review found four such changes in
the history (2263eb6b inserted three members into ServerStatus before `sessions`; 03dd8e68 appended two
to a published SessionScore; 9c98ab75 and 5724e6bf renamed members), none caught.

Each struct, enum and constant of the IDL is reduced to one line, comments out and blanks collapsed:
  struct NAME [annotations]: member; member; ...   (a member: annotations, type with bounds, name, array)
  enum NAME: A, B, C
  const TYPE NAME = VALUE
Every baseline line must be in the IDL unchanged; a struct, enum or constant the baseline does not have
is allowed (the contract grows by adding) and named, to be added with --write. The checker also runs on
three altered copies of the IDL each time (a member inserted, one renamed, @final dropped) and must
refuse each, so that a parser that read nothing would not pass.
"""
import re
import sys


def entries(text):
    """name -> one-line form, in the file's order."""
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    text = re.sub(r"//[^\n]*", " ", text)
    text = re.sub(r"\s+", " ", text)
    out = {}
    for m in re.finditer(r"((?:@\w+(?:\([^)]*\))?\s*)*)\b(struct|enum)\s+(\w+)\s*\{([^}]*)\}", text):
        ann = " ".join(m.group(1).split())
        kind, name, body = m.group(2), m.group(3), m.group(4)
        if kind == "struct":
            members = [" ".join(x.split()) for x in body.split(";") if x.strip()]
            members = [re.sub(r">(\w)", r"> \1", re.sub(r"\s*([<>,\[\]])\s*", r"\1", x).replace(",", ", "))
                       for x in members]
            out["struct " + name] = "struct %s%s: %s" % (name, " " + ann if ann else "", "; ".join(members))
        else:
            out["enum " + name] = "enum %s: %s" % (name, ", ".join(x.strip() for x in body.split(",") if x.strip()))
    for m in re.finditer(r"\bconst\s+([\w ]+?)\s+(\w+)\s*=\s*([^;]+);", text):
        out["const " + m.group(2)] = "const %s %s = %s" % (" ".join(m.group(1).split()), m.group(2), m.group(3).strip())
    return out


def compare(idl_text, base_lines):
    """(problems, new names)."""
    now = entries(idl_text)
    problems = []
    seen = set()
    for line in base_lines:
        if line.startswith("const "):
            kind_name = "const " + line.split("=")[0].split()[-1]
        else:
            kind_name = " ".join(line.split(":")[0].split()[:2])
        seen.add(kind_name)
        if kind_name not in now:
            problems.append("%s: removed or renamed (baseline: %s)" % (kind_name, line))
        elif now[kind_name] != line:
            problems.append("%s changed:\n    baseline: %s\n    now:      %s" % (kind_name, line, now[kind_name]))
    return problems, [k for k in now if k not in seen]


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    idl, base = sys.argv[1], sys.argv[2]
    with open(idl) as f:
        text = f.read()
    if len(sys.argv) > 3 and sys.argv[3] == "--write":
        with open(base, "w") as f:
            f.write("# The wire contract: idl/palp_types.idl's structs, enums and constants, one a line\n"
                    "# (tests/interop/idl_baseline.py --write; change it only to change the contract on purpose).\n")
            for v in entries(text).values():
                f.write(v + "\n")
        print("wrote %s: %d entries" % (base, len(entries(text))))
        return 0
    with open(base) as f:
        lines = [l.rstrip("\n") for l in f if l.strip() and not l.startswith("#")]
    failures = 0
    problems, new = compare(text, lines)
    structs = sum(1 for l in lines if l.startswith("struct "))
    if problems:
        failures += 1
        print("FAIL the wire contract changed (a type grows only by a new topic; a deliberate change is a new "
              "baseline: idl_baseline.py IDL BASELINE --write):")
        for p in problems:
            print("  " + p)
    else:
        print("ok   %d baseline entries (%d structs) unchanged in %s" % (len(lines), structs, idl))
    for n in new:
        print("NOTE %s is new (allowed: the contract grows by adding); add it to the baseline with --write" % n)
    # The checker itself, on altered copies: each must be refused.
    alter = [
        ("a member inserted before ServerStatus.sessions",
         lambda t: t.replace("sequence<SessionLoad> sessions;", "unsigned long extra; sequence<SessionLoad> sessions;", 1)),
        ("SessionScore.log_uid renamed", lambda t: re.sub(r"\blog_uid;", "log_session;", t, count=1)),
        ("@final dropped from Vec3", lambda t: re.sub(r"@final(\s+struct Vec3\b)", r"@appendable\1", t, count=1)),
    ]
    for what, f in alter:
        t = f(text)
        p, _ = compare(t, lines)
        if t == text or not p:
            failures += 1
            print("FAIL the checker passed an IDL with %s%s" % (what, " (the alteration did not apply)" if t == text else ""))
        else:
            print("ok   the checker refuses an IDL with %s: %s" % (what, p[0].splitlines()[0]))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
