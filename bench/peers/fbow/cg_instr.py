#!/usr/bin/env python3
"""Per-instruction exclusive Ir of one function from a callgrind --dump-instr=yes
file, joined with objdump's disassembly of the binary.
  cg_instr.py CALLGRIND.out BINARY 'function substring' [divisor]"""
import re, subprocess, sys
out, binary, pat = sys.argv[1:4]
div = float(sys.argv[4]) if len(sys.argv) > 4 else 1.0
names = {}
cost = {}
cur = None
addr = 0
skip_next = False
for line in open(out):
    line = line.rstrip('\n')
    m = re.match(r'^(c?fn)=\((\d+)\)(?: (.*))?$', line)
    if m:
        if m.group(3): names[m.group(2)] = m.group(3)
        if m.group(1) == 'fn':
            cur = m.group(2)
        continue
    if line.startswith('calls='):
        skip_next = True
        continue
    m = re.match(r'^(0x[0-9a-f]+|\+\d+|-\d+|\*)\s+\S+\s+(\d+)', line)
    if m and cur is not None:
        a = m.group(1)
        if a.startswith('0x'): addr = int(a, 16)
        elif a[0] == '+': addr += int(a[1:])
        elif a[0] == '-': addr -= int(a[1:])
        if skip_next:
            skip_next = False
            continue
        if pat in names.get(cur, ''):
            cost[addr] = cost.get(addr, 0) + int(m.group(2))
        continue
    m = re.match(r'^(0x[0-9a-f]+|\+\d+|-\d+|\*)\b', line)
    if m:
        a = m.group(1)
        if a.startswith('0x'): addr = int(a, 16)
        elif a[0] == '+': addr += int(a[1:])
        elif a[0] == '-': addr -= int(a[1:])
        if skip_next: skip_next = False
lo, hi = min(cost), max(cost)
dis = subprocess.run(['objdump', '-d', '--no-show-raw-insn', f'--start-address={lo}',
                      f'--stop-address={hi + 1}', binary], capture_output=True, text=True).stdout
total = 0
for l in dis.splitlines():
    m = re.match(r'^\s+([0-9a-f]+):\s+(.*)$', l)
    if not m: continue
    a = int(m.group(1), 16)
    c = cost.get(a, 0)
    total += c
    print(f'{c/div:10.2f}  {a:x}  {m.group(2)[:70]}')
print(f'total {total/div:.2f}')
