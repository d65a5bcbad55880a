"""Turn the `RESULT case phase key=value ...` lines of benches/multigrid.rs,
scripts/pyamg_baseline.py (phase pyamg) and scripts/hypre_baseline.py
(phase hypre: BoomerAMG-CG through petsc4py, one rank) on stdin into one
table: hasse next to its baseline, with the ratio hasse / baseline (below
1: hasse is faster or smaller). Structured cases (phases mg, mg-pc, sa,
direct, solve, plain, q1-solve, q1-assembly, q1-plain, amd, nd), perturbed
Kuhn cases (phase amg) and Delaunay cases (phases amg, dec, direct, plain,
amd, nd, check) get their own rows; a failed phase shows as — in its rows.
The AMG rows ("AMG against hypre") compare smoothed aggregation with both
baselines and its peak memory with the matrix's own (PETSc's count of the
assembled AIJ matrix, `matrix_gib` of the hypre line)."""
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
    # Three decimals for memory: a 10⁶-unknown matrix is under 0.1 GiB.
    return "—" if v is None else (f"{v:.3f} {unit}" if unit == "GiB" else f"{v:.2f} {unit}")


def ratio(a, b):
    return "—" if a is None or b is None or b == 0 else f"{a / b:.2f}"


def it(d):
    """Iterations and final relative residual of a run, for a row label."""
    return f"{d.get('iterations', '?')} it, r={d.get('residual', '?')}"


def add(*parts):
    """Sum of the parts, or None when one is missing."""
    return None if any(p is None for p in parts) else sum(parts)


ORDERING = {"nd": "nested dissection", "amd": "AMD", "geometric": "geometric ND"}


def ordering_rows(label, r):
    """LLᵀ of the hand-built matrix through hasse with nested dissection
    (phase nd) next to faer's own LLᵀ (plain, AMD) and hasse with AMD (amd),
    all in the same run."""
    nd, amd, plain = (r.get(p, {}) for p in ("nd", "amd", "plain"))
    if not nd and not amd:
        return []
    mega = lambda d: None if num(d, "entries") is None else num(d, "entries") / 1e6
    return [
        (label, "LLᵀ analysis+factorisation, nested dissection", fmt(num(nd, "factor")), "plain faer LLᵀ (AMD)", fmt(num(plain, "factor")), ratio(num(nd, "factor"), num(plain, "factor"))),
        (label, "  same, nested dissection", fmt(num(nd, "factor")), "hasse LLᵀ, AMD", fmt(num(amd, "factor")), ratio(num(nd, "factor"), num(amd, "factor"))),
        (label, "  analysis alone (METIS + symbolic)", fmt(num(nd, "analysis")), "AMD + symbolic", fmt(num(amd, "analysis")), ratio(num(nd, "analysis"), num(amd, "analysis"))),
        (label, "  numeric factorisation alone", fmt(num(nd, "numeric")), "AMD", fmt(num(amd, "numeric")), ratio(num(nd, "numeric"), num(amd, "numeric"))),
        (label, "  solve", fmt(num(nd, "solve")), "AMD", fmt(num(amd, "solve")), ratio(num(nd, "solve"), num(amd, "solve"))),
        (label, "  factor entries", fmt(mega(nd), "M"), "AMD", fmt(mega(amd), "M"), ratio(mega(nd), mega(amd))),
        (label, "  peak memory, analysis+factorisation+solve", fmt(num(nd, "solve_peak_gib"), "GiB"), "AMD", fmt(num(amd, "solve_peak_gib"), "GiB"), ratio(num(nd, "solve_peak_gib"), num(amd, "solve_peak_gib"))),
    ]


def delaunay_rows(label, r):
    """Nodal P1 on a Delaunay mesh (phases amg, dec, direct, solve, plain,
    check and pyamg): the FE assembly, DEC assembly and LLᵀ next to the hand-built
    matrix and faer's own LLᵀ, AMG-CG next to pyamg."""
    fe, dec, direct, plain, amg, check = (
        r.get(p, {}) for p in ("amg", "dec", "direct", "plain", "pyamg", "check")
    )
    out = []
    complex_s = num(fe, "complex") or num(direct, "complex")
    out.append((label, f"complex: generate::delaunay ({fe.get('triangles', '?')} triangles)", fmt(complex_s), "(no baseline: spade is not a bench dependency)", "—", "—"))
    for name, run in (("FE", fe), ("DEC", dec)):
        out.append((label, f"{name} assembly (Ω, AᵀΩA, b)", fmt(num(run, "assembly")), "plain P1 triplets", fmt(num(plain, "assembly")), ratio(num(run, "assembly"), num(plain, "assembly"))))
    if check:
        agreement = f"FE {check.get('fe_vs_plain', '?')}, DEC {check.get('dec_vs_plain', '?')}, u {check.get('solution_vs_plain', '?')}"
        out.append((label, "  max rel. difference to the plain system", agreement, f"plain P1, nnz {check.get('nnz', '?')}", "—", "—"))
    used = ORDERING.get(direct.get("ordering"), "?")
    out.append((label, f"LLᵀ analysis+factorisation (FE, {used})", fmt(num(direct, "factor")), "faer LLᵀ, plain matrix", fmt(num(plain, "factor")), ratio(num(direct, "factor"), num(plain, "factor"))))
    out.append((label, f"LLᵀ solve (r={direct.get('residual', '?')})", fmt(num(direct, "solve")), f"faer LLᵀ (r={plain.get('residual', '?')})", fmt(num(plain, "solve")), ratio(num(direct, "solve"), num(plain, "solve"))))
    amg_total = add(num(amg, "setup"), num(amg, "solve"))
    for name, run in (("FE", fe), ("DEC", dec)):
        total = add(num(run, "setup"), num(run, "solve"))
        out.append((label, f"{name} SA-AMG setup + CG to 1e-8 ({it(run)})", fmt(total), f"pyamg SA-CG ({it(amg)})", fmt(amg_total), ratio(total, amg_total)))
    out.append((label, "  AMG setup alone (FE)", fmt(num(fe, "setup")), "pyamg setup", fmt(num(amg, "setup")), ratio(num(fe, "setup"), num(amg, "setup"))))
    out.append((label, "  CG iterations alone (FE)", fmt(num(fe, "solve")), "pyamg solve", fmt(num(amg, "solve")), ratio(num(fe, "solve"), num(amg, "solve"))))
    out += [row for row in amg_rows(label, fe, {"hypre": r.get("hypre", {})}, "FE SA-AMG")]
    # The solve-alone peaks are read with the complex dropped (the process
    # holds M and b as pyamg's does); the whole-run peaks include the complex.
    for what, key in (("AMG-CG (FE) alone", "solve_peak_gib"), ("whole FE AMG run", "peak_gib")):
        out.append((label, f"peak memory, {what}", fmt(num(fe, key), "GiB"), "pyamg process", fmt(num(amg, "peak_gib"), "GiB"), ratio(num(fe, key), num(amg, "peak_gib"))))
    for what, key in (("LLᵀ alone", "solve_peak_gib"), ("whole direct run", "peak_gib")):
        out.append((label, f"peak memory, {what}", fmt(num(direct, key), "GiB"), "plain build+LLᵀ process", fmt(num(plain, "peak_gib"), "GiB"), ratio(num(direct, key), num(plain, "peak_gib"))))
    e2e = add(complex_s, num(fe, "assembly"), num(fe, "setup"), num(fe, "solve"))
    direct_e2e = add(num(direct, "complex"), num(direct, "assembly"), num(direct, "factor"), num(direct, "solve"))
    out.append((label, "end to end AMG (complex+FE assembly+AMG-CG)", fmt(e2e), "hasse direct end to end", fmt(direct_e2e), ratio(e2e, direct_e2e)))
    hasse_direct = add(num(direct, "assembly"), num(direct, "factor"), num(direct, "solve"))
    plain_total = add(num(plain, "assembly"), num(plain, "factor"), num(plain, "solve"))
    out.append((label, "FE assembly + LLᵀ + solve", fmt(hasse_direct), "plain build+LLᵀ+solve", fmt(plain_total), ratio(hasse_direct, plain_total)))
    whole = r.get("solve", {})
    if whole:
        used = ORDERING.get(whole.get("ordering"), "?")
        beside = " (analysis beside assembly)" if whole.get("beside") == "true" else ""
        out.append((label, f"whole P1 Diffusion::solve{beside}, {used}", fmt(num(whole, "whole")), "plain faer LLᵀ analysis+factorisation", fmt(num(plain, "factor")), ratio(num(whole, "whole"), num(plain, "factor"))))
    return out + ordering_rows(label, r)


def amg_rows(label, run, r, what):
    """Smoothed-aggregation AMG-CG (`run`: phase sa or amg) against hypre
    BoomerAMG-CG and pyamg on the same matrix, and its solve's peak memory
    against the matrix's own."""
    hypre, pyamg = r.get("hypre", {}), r.get("pyamg", {})
    if not hypre and not pyamg:
        return []
    total = add(num(run, "setup"), num(run, "solve"))
    out = []
    for name, base in (("hypre BoomerAMG-CG, 1 rank", hypre), ("pyamg SA-CG", pyamg)):
        if base:
            base_total = add(num(base, "setup"), num(base, "solve"))
            out.append((label, f"{what} setup + CG to 1e-8 ({it(run)})", fmt(total), f"{name} ({it(base)})", fmt(base_total), ratio(total, base_total)))
            out.append((label, "  AMG setup alone", fmt(num(run, "setup")), f"{name.split(',')[0].split(' SA')[0]} setup", fmt(num(base, "setup")), ratio(num(run, "setup"), num(base, "setup"))))
            out.append((label, "  CG alone", fmt(num(run, "solve")), f"{name.split(',')[0].split(' SA')[0]} solve", fmt(num(base, "solve")), ratio(num(run, "solve"), num(base, "solve"))))
    peak = num(run, "solve_peak_gib")
    if hypre:
        out.append((label, "  peak memory, AMG setup + CG (matrix held)", fmt(peak, "GiB"), "the matrix alone (PETSc AIJ)", fmt(num(hypre, "matrix_gib"), "GiB"), ratio(peak, num(hypre, "matrix_gib"))))
        out.append((label, "  same", fmt(peak, "GiB"), "hypre process (file read included)", fmt(num(hypre, "peak_gib"), "GiB"), ratio(peak, num(hypre, "peak_gib"))))
    return out


def kuhn_rows(label, r):
    """Nodal P1 on the perturbed Kuhn box: complex, assembly, and AMG-CG
    against hypre and pyamg."""
    fe = r.get("amg", {})
    out = [(label, f"complex: kuhn + perturb ({fe.get('tetrahedra', '?')} tetrahedra)", fmt(num(fe, "complex")), "—", "—", "—"),
           (label, "FE assembly (Ω, AᵀΩA, b)", fmt(num(fe, "assembly")), "—", "—", "—")]
    return out + amg_rows(label, fe, r, "P1 SA-AMG")


def mg_total_of(mg):
    return add(num(mg, "setup"), num(mg, "solve"))


rows = []
for case in runs:
    r = runs[case]
    if case.startswith("kuhn-"):
        n = r.get("amg", {}).get("unknowns") or r.get("hypre", {}).get("unknowns") or "?"
        rows += kuhn_rows(f"{case} ({n})", r)
        continue
    if "amg" in r or "check" in r:
        fe, direct, plain = (r.get(p, {}) for p in ("amg", "direct", "plain"))
        n = fe.get("unknowns") or direct.get("unknowns") or plain.get("unknowns") or "?"
        rows += delaunay_rows(f"{case} ({n})", r)
        continue
    mg, direct, plain, amg = (r.get(p, {}) for p in ("mg", "direct", "plain", "pyamg"))
    n = (mg.get("unknowns") or direct.get("unknowns") or plain.get("unknowns") or r.get("nd", {}).get("unknowns")
         or r.get("sa", {}).get("unknowns") or r.get("hypre", {}).get("unknowns") or "?")
    label = f"{case} ({n})"
    assembly = num(mg, "assembly") or num(direct, "assembly")
    rows.append((label, "assembly (Ω, AᵀΩA, b)", fmt(assembly), "plain triplets", fmt(num(plain, "assembly")), ratio(assembly, num(plain, "assembly"))))
    used = ORDERING.get(direct.get("ordering"), "?")
    rows.append((label, f"LLᵀ analysis+factorisation ({used})", fmt(num(direct, "factor")), "plain faer LLᵀ (AMD)", fmt(num(plain, "factor")), ratio(num(direct, "factor"), num(plain, "factor"))))
    rows.append((label, "LLᵀ solve", fmt(num(direct, "solve")), "plain faer LLᵀ", fmt(num(plain, "solve")), ratio(num(direct, "solve"), num(plain, "solve"))))
    whole = r.get("solve", {})
    if whole:
        beside = " (analysis beside assembly)" if whole.get("beside") == "true" else ""
        rows.append((label, f"whole Diffusion::solve{beside}, {ORDERING.get(whole.get('ordering'), '?')}", fmt(num(whole, "whole")), "plain faer LLᵀ analysis+factorisation", fmt(num(plain, "factor")), ratio(num(whole, "whole"), num(plain, "factor"))))
    q1, q1_plain = r.get("q1-solve", {}), r.get("q1-plain", {})
    if q1 or q1_plain:
        beside = " (analysis beside assembly)" if q1.get("beside") == "true" else ""
        q1_label = f"{case} Q1 ({q1.get('unknowns') or q1_plain.get('unknowns') or '?'})"
        rows.append((q1_label, f"nodal Q1 whole Diffusion::solve{beside}", fmt(num(q1, "whole")), "plain faer LLᵀ analysis+factorisation", fmt(num(q1_plain, "factor")), ratio(num(q1, "whole"), num(q1_plain, "factor"))))
        rows.append((q1_label, "  assembly (geometry, Ω, AᵀΩA, b)", fmt(num(q1, "assembly")), "plain Q1 triplets", fmt(num(q1_plain, "assembly")), ratio(num(q1, "assembly"), num(q1_plain, "assembly"))))
        rows.append((q1_label, f"  LLᵀ analysis + numeric ({ORDERING.get(q1.get('ordering'), '?')})", fmt(add(num(q1, "analysis"), num(q1, "numeric"))), "plain faer LLᵀ (AMD)", fmt(num(q1_plain, "factor")), ratio(add(num(q1, "analysis"), num(q1, "numeric")), num(q1_plain, "factor"))))
        rows.append((q1_label, "  assembly against its own LLᵀ", fmt(num(q1, "assembly")), "hasse LLᵀ analysis + numeric", fmt(add(num(q1, "analysis"), num(q1, "numeric"))), ratio(num(q1, "assembly"), add(num(q1, "analysis"), num(q1, "numeric")))))
        alone = r.get("q1-assembly", {})
        if alone:
            rows.append((q1_label, "  assembly alone (q1-assembly) against its own LLᵀ", fmt(num(alone, "assembly")), "hasse LLᵀ analysis + numeric", fmt(add(num(q1, "analysis"), num(q1, "numeric"))), ratio(num(alone, "assembly"), add(num(q1, "analysis"), num(q1, "numeric")))))
        rows.append((q1_label, "  peak memory", fmt(num(q1, "peak_gib"), "GiB"), "plain faer process", fmt(num(q1_plain, "peak_gib"), "GiB"), ratio(num(q1, "peak_gib"), num(q1_plain, "peak_gib"))))
    mg_setup, mg_solve = num(mg, "setup"), num(mg, "solve")
    mg_total = None if mg_setup is None else mg_setup + mg_solve
    amg_total = None if num(amg, "setup") is None else num(amg, "setup") + num(amg, "solve")
    rows.append((label, f"MG setup + CG to 1e-8 ({mg.get('iterations', '?')} it)", fmt(mg_total), f"pyamg SA-CG ({amg.get('iterations', '?')} it)", fmt(amg_total), ratio(mg_total, amg_total)))
    sa = r.get("sa", {})
    if sa:
        sa_total = None if num(sa, "setup") is None else num(sa, "setup") + num(sa, "solve")
        rows.append((label, f"  AMG (smoothed aggregation, matrix alone) setup + CG ({sa.get('iterations', '?')} it)", fmt(sa_total), "pyamg SA-CG", fmt(amg_total), ratio(sa_total, amg_total)))
        rows.append((label, "    AMG setup alone", fmt(num(sa, "setup")), "pyamg setup", fmt(num(amg, "setup")), ratio(num(sa, "setup"), num(amg, "setup"))))
        rows += amg_rows(label, sa, {"hypre": r.get("hypre", {})}, "AMG (sa)")
    hypre = r.get("hypre", {})
    if hypre and mg:
        hypre_total = add(num(hypre, "setup"), num(hypre, "solve"))
        rows.append((label, f"MG setup + CG to 1e-8 ({mg.get('iterations', '?')} it)", fmt(mg_total_of(mg)), f"hypre BoomerAMG-CG ({it(hypre)})", fmt(hypre_total), ratio(mg_total_of(mg), hypre_total)))
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
    rows += ordering_rows(label, r)

head = ("case (unknowns)", "hasse", "", "baseline", "", "hasse/baseline")
widths = [max(len(str(r[i])) for r in rows + [head]) for i in range(6)]
line = lambda r: "  ".join(str(c).ljust(w) for c, w in zip(r, widths))
print(line(head))
print("  ".join("-" * w for w in widths))
for r in rows:
    print(line(r))

failed = [(case, phase, f["failed"]) for case in runs for phase, f in runs[case].items() if "failed" in f]
if failed:
    print("\nfailed phases:")
    for case, phase, why in failed:
        print(f"  {case} {phase} {why}")
