"""Turn the `RESULT case phase key=value ...` lines of benches/multigrid.rs
and scripts/pyamg_baseline.py (stdin) into one table: hasse next to its
baseline, with the ratio hasse / baseline (below 1: hasse is faster or
smaller)."""
import sys
from collections import defaultdict

runs = defaultdict(dict)
for line in sys.stdin:
    parts = line.split()
    if len(parts) < 3 or parts[0] != "RESULT":
        continue
    case, phase = parts[1], parts[2]
    fields = dict(p.split("=", 1) for p in parts[3:] if "=" in p)
    if "=" not in " ".join(parts[3:4]):
        fields["failed"] = " ".join(parts[3:])
    runs[case][phase] = fields


def num(d, k):
    try:
        return float(d[k])
    except (KeyError, ValueError, TypeError):
        return None


def fmt(v, unit="s"):
    return "—" if v is None else f"{v:.2f} {unit}"


def ratio(a, b):
    return "—" if a is None or b is None or b == 0 else f"{a / b:.2f}"


rows = []
for case in runs:
    r = runs[case]
    mg, direct, plain, amg = (r.get(p, {}) for p in ("mg", "direct", "plain", "pyamg"))
    n = mg.get("unknowns") or direct.get("unknowns") or plain.get("unknowns") or "?"
    label = f"{case} ({n})"
    assembly = num(mg, "assembly") or num(direct, "assembly")
    rows.append((label, "assembly (Ω, AᵀΩA, b)", fmt(assembly), "plain triplets", fmt(num(plain, "assembly")), ratio(assembly, num(plain, "assembly"))))
    rows.append((label, "LLᵀ analysis+factorisation", fmt(num(direct, "factor")), "plain faer LLᵀ", fmt(num(plain, "factor")), ratio(num(direct, "factor"), num(plain, "factor"))))
    rows.append((label, "LLᵀ solve", fmt(num(direct, "solve")), "plain faer LLᵀ", fmt(num(plain, "solve")), ratio(num(direct, "solve"), num(plain, "solve"))))
    mg_setup, mg_solve = num(mg, "setup"), num(mg, "solve")
    mg_total = None if mg_setup is None else mg_setup + mg_solve
    amg_total = None if num(amg, "setup") is None else num(amg, "setup") + num(amg, "solve")
    rows.append((label, f"MG setup + CG to 1e-8 ({mg.get('iterations', '?')} it)", fmt(mg_total), f"pyamg SA-CG ({amg.get('iterations', '?')} it)", fmt(amg_total), ratio(mg_total, amg_total)))
    pc = r.get("mg-pc", {})
    pc_total = None if num(pc, "setup") is None else num(pc, "setup") + num(pc, "solve")
    rows.append((label, f"  same, constant P, correction 2 ({pc.get('iterations', '?')} it)", fmt(pc_total), f"pyamg SA-CG", fmt(amg_total), ratio(pc_total, amg_total)))
    rows.append((label, "  peak memory, constant-P run", fmt(num(pc, "peak_gib"), "GiB"), "pyamg process", fmt(num(amg, "peak_gib"), "GiB"), ratio(num(pc, "peak_gib"), num(amg, "peak_gib"))))
    e2e = None if mg_total is None else num(mg, "complex") + assembly + mg_total
    direct_e2e = None if num(direct, "factor") is None else num(direct, "complex") + assembly + num(direct, "factor") + num(direct, "solve")
    rows.append((label, "end to end MG (complex+assembly+MG)", fmt(e2e), "hasse direct end to end", fmt(direct_e2e), ratio(e2e, direct_e2e)))
    plain_total = None if num(plain, "factor") is None else num(plain, "assembly") + num(plain, "factor") + num(plain, "solve")
    rows.append((label, "assembly + MG-CG", fmt(None if mg_total is None else assembly + mg_total), "plain faer build+LLᵀ+solve", fmt(plain_total), ratio(None if mg_total is None else assembly + mg_total, plain_total)))
    rows.append((label, "peak memory, MG run", fmt(num(mg, "peak_gib"), "GiB"), "pyamg process", fmt(num(amg, "peak_gib"), "GiB"), ratio(num(mg, "peak_gib"), num(amg, "peak_gib"))))
    rows.append((label, "peak memory, direct run", fmt(num(direct, "peak_gib"), "GiB"), "plain faer process", fmt(num(plain, "peak_gib"), "GiB"), ratio(num(direct, "peak_gib"), num(plain, "peak_gib"))))

head = ("case (unknowns)", "hasse", "", "baseline", "", "hasse/baseline")
widths = [max(len(str(r[i])) for r in rows + [head]) for i in range(6)]
line = lambda r: "  ".join(str(c).ljust(w) for c, w in zip(r, widths))
print(line(head))
print("  ".join("-" * w for w in widths))
for r in rows:
    print(line(r))
