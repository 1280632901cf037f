#!/usr/bin/env python3
"""CPU seconds `tridex simulate` spends on one thread while its others wait, from a profile.

Usage: perf record -F HZ -g -o run.data build/tools/tridex simulate ... --threads 2
       python3 bench/serial_cpu.py run.data HZ [WINDOW_S]

The samples are cut into windows of WINDOW_S seconds (0.1 by default). A window where only one
of the process's threads was sampled is serial work: on a quiet 2-core machine the other core
idles through it. A window where one thread has more than twice the samples of the next is
counted as imbalance (the busiest thread's excess). Both are listed by the first frames of the
call chain (" [zeroing]": the kernel zeroing fresh pages under it). Unlike wall times, these
figures hold under load: a thread that waits is not sampled, however slow the machine
(bench/README.md, issue 37).
"""
import collections
import re
import subprocess
import sys

KERNEL_FRAMES = ("clear_page", "folio_", "vma_", "do_", "__", "handle_", "exc_", "asm_", "entry_",
                 "x64")


def short(symbol):
    symbol = re.sub(r"\(.*", "", symbol)
    for _ in range(4):
        symbol = re.sub(r"<[^<>]*>", "", symbol)
    return symbol.split("::")[-1][:24]


def samples(data):
    text = subprocess.run(["perf", "script", "-i", data, "-F", "tid,time,ip,sym"],
                          capture_output=True, text=True, check=True).stdout
    for block in text.split("\n\n"):
        lines = block.strip().split("\n")
        head = re.match(r"\s*(\d+)\s+([\d.]+):", lines[0]) if lines else None
        if not head:
            continue
        frames = [short(line.strip().split(None, 1)[1]) for line in lines[1:]
                  if len(line.strip().split(None, 1)) > 1]
        user = [f for f in frames if f and not f.startswith(KERNEL_FRAMES)]
        tag = " < ".join(user[:4]) + (" [zeroing]" if "clear_page_erms" in frames else "")
        yield float(head.group(2)), int(head.group(1)), tag


def main():
    data, hz = sys.argv[1], float(sys.argv[2])
    window = float(sys.argv[3]) if len(sys.argv) > 3 else 0.1
    all_samples = sorted(samples(data))
    serial, excess = collections.Counter(), collections.Counter()
    i = 0
    while i < len(all_samples):
        j = i
        while j < len(all_samples) and all_samples[j][0] < all_samples[i][0] + window:
            j += 1
        part = all_samples[i:j]
        per_thread = collections.Counter(tid for _, tid, _ in part)
        if len(per_thread) == 1:
            for _, _, tag in part:
                serial[tag] += 1
        else:
            (busiest, most), (_, next_most) = per_thread.most_common(2)
            if most > 2 * next_most:
                for _, tid, tag in part:
                    if tid == busiest:
                        excess[tag] += (most - next_most) / most
        i = j
    print(f"all samples {len(all_samples) / hz:.2f} s CPU; serial windows "
          f"{sum(serial.values()) / hz:.2f} s; imbalance excess {sum(excess.values()) / hz:.2f} s")
    for tag, n in serial.most_common(12):
        print(f"  serial    {n / hz:5.2f} s  {tag}")
    for tag, n in excess.most_common(12):
        print(f"  imbalance {n / hz:5.2f} s  {tag}")


if __name__ == "__main__":
    main()
