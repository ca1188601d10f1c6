#!/usr/bin/env python3
"""Where a run's open-close passes go, from the stderr of `DDA3D_DEBUG=1 dda3d run ...`.

Usage: open-close-tail.py LOG [TAIL_PASS]

Prints the state changes of each pass (over all steps), the changes from pass TAIL_PASS on
(default 8: "the tail") by kind, and how many of them were a contact's first change of its
step, the steps with the most passes with their changes pass by pass, and the contacts that
changed most often within one step. Lines are those of `log_change` in
src/solver/open_close.rs; a contact is its pair, mode and features (older logs without the
`features=` field lump the contacts of one pair and mode together).
"""
import collections
import re
import signal
import sys

LINE = re.compile(
    r"t=(?P<t>\S+) dt=\S+ pass (?P<pass>\d+): (?P<old>\w+)->(?P<new>\w+) mode=(?P<mode>\d)"
    r".* pair=(?P<pair>\S+)(?: flips=(?P<flips>\d+) started=(?P<started>\w+)"
    r" features=(?P<features>\S+))?"
)


def main():
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # quiet under `| head`
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    tail_from = int(sys.argv[2]) if len(sys.argv) == 3 else 8
    per_pass = collections.Counter()
    tail = collections.Counter()
    tail_first = collections.Counter()
    by_step = collections.defaultdict(collections.Counter)
    history = collections.defaultdict(list)
    with open(sys.argv[1], encoding="utf-8", errors="replace") as f:
        for line in f:
            m = LINE.match(line)
            if not m:
                continue
            p = int(m["pass"])
            kind = f"{m['old']}->{m['new']}"
            contact = f"{m['pair']}/{m['mode']}" + (f"/{m['features']}" if m["features"] else "")
            per_pass[p] += 1
            by_step[m["t"]][p] += 1
            history[(m["t"], contact)].append((p, kind))
            if p >= tail_from:
                tail[kind] += 1
                first = int(m["flips"]) == 1 if m["flips"] else len(history[(m["t"], contact)]) == 1
                tail_first[kind] += first
    if not per_pass:
        sys.exit("no state changes in the log (was it run with DDA3D_DEBUG=1?)")
    print("state changes per pass (all steps):")
    print("  " + ", ".join(f"{p}: {n}" for p, n in sorted(per_pass.items())))
    print(f"from pass {tail_from} on, by kind (first change of the contact in its step):")
    for kind, n in tail.most_common():
        print(f"  {kind:12} {n:7} ({tail_first[kind]} first)")
    longest = sorted(by_step.items(), key=lambda kv: -max(kv[1]))[:3]
    for t, passes in longest:
        print(f"step ending t = {t}: {max(passes)} passes; changes by pass:")
        print("  " + ", ".join(f"{p}: {n}" for p, n in sorted(passes.items())))
    print("contacts with the most changes in one step:")
    for (t, contact), h in sorted(history.items(), key=lambda kv: -len(kv[1]))[:8]:
        print(f"  t = {t} {contact}: " + ", ".join(f"{p} {k}" for p, k in h))


if __name__ == "__main__":
    main()
