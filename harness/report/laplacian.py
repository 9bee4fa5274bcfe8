"""The Laplacian task's extra report section: the Wardetzky et al. 2007 property matrix."""
from __future__ import annotations

from .common import esc as _esc
from .common import fmt as _fmt
from ..schema import scalar as _clean
from .common import natural_key, noise_label, variant_labels

PROPS = [("SYM", "SYM", "sym_error", "max |W-Wᵀ| / max|W|"),
         ("LOC", "LOC", "loc_violations", "non-zeros between vertices sharing no edge"),
         ("LIN", "LIN", "lin_error", "max |W X| / (max|W| diag), planar meshes only"),
         ("POS", "POS", "neg_weights", "fraction of negative off-diagonal weights"),
         ("PSD", "psd", "min_eig", "symmetric W: smallest eigenvalue of -W, relative; non-symmetric W: every "
                                   "eigenvalue of -W has a non-negative real part (exact certificate, else blank)")]


def property_matrix(df, defaults=None) -> list[dict]:
    """Per operator variant (labelled as everywhere in the report: ``defaults`` are the methods'
    defaults from run.json): for each property, whether it holds on every measured row and the worst size."""
    labels = variant_labels(df, (), defaults) if len(df) else []     # from every row, as the tables label them
    ok = df.assign(_variant=labels)[df["status"] == "ok"].copy()
    out = []
    for var in sorted(ok["_variant"].unique(), key=natural_key) if len(ok) else []:
        g = ok[ok["_variant"] == var]
        entry = {"variant": var, "n": len(g), "props": {}}
        for label, flag, val, _ in PROPS + [("M⁻¹W sym", "operator_symmetric", None, "")]:
            if flag not in g:
                continue
            flags = g[flag].dropna()
            measured = len(flags)
            fails = g.loc[flags.index][flags.astype(bool) == False]  # noqa: E712
            worst = None
            if val and val in g and g[val].notna().any():
                col = g[val].astype(float)
                worst = float(col.min()) if val == "min_eig" else float(col.max())
            per_mesh = [(str(r.mesh), noise_label(r.noise_model, r.noise_level), _clean(getattr(r, flag)),
                         _clean(getattr(r, val)) if val else None) for r in g.itertuples(index=False)]
            entry["props"][label] = {"measured": measured, "fails": len(fails), "worst": worst, "rows": per_mesh,
                                     "fail_meshes": sorted(set(fails["mesh"].astype(str)))}
        out.append(entry)
    return out


def _matrix_html(df, defaults=None) -> str:
    mat = property_matrix(df, defaults)
    if not mat:
        return "<p class='warn'>No Laplacian row with status ok: no property matrix.</p>"
    labels = [p[0] for p in PROPS] + ["M⁻¹W sym"]
    docs = {p[0]: p[3] for p in PROPS}
    docs["M⁻¹W sym"] = "the pointwise operator M⁻¹W itself is symmetric (not one of the four)"
    head = "".join(f"<th title='{_esc(docs[lb])}'>{lb}</th>" for lb in labels)
    body = []
    for e in mat:
        cells = []
        for lb in labels:
            p = e["props"].get(lb)
            if p is None or p["measured"] == 0:
                why = "LIN is measured on planar meshes only" if lb == "LIN" else "not measured"
                cells.append(f"<td class='na' title='{why}'>n/a</td>")
                continue
            tip = "\n".join(f"{m}, {nz}: {'holds' if f else 'fails'}" + (f" ({_fmt(v)})" if v is not None else "")
                            for m, nz, f, v in p["rows"] if f is not None)
            size = ""
            if p["worst"] is not None:
                kind = "min" if lb == "PSD" else "max"
                worst = p["worst"]
                shown = (str(int(worst)) if lb == "LOC" and float(worst).is_integer() else _fmt(worst))  # a count
                size = f"<span class='size'>{kind} {shown}</span>"
            if p["fails"] == 0:
                cells.append(f"<td class='yes' title='{_esc(tip)}'>✓ <small>{p['measured']}/{p['measured']}</small>{size}</td>")
            else:
                cells.append(f"<td class='no' title='{_esc(tip)}'>✗ <small>fails {p['fails']}/{p['measured']}</small>{size}</td>")
        body.append(f"<tr><th>{_esc(e['variant'])}</th>{''.join(cells)}</tr>")
    return (f"<table class='propmatrix'><tr><th>operator</th>{head}</tr>{''.join(body)}</table>"
            "<p class='caption'>✓: the property holds on every measured mesh (count shown); ✗: it fails on the "
            "given number of them. The small number is the worst violation size over the meshes "
            "(<code>sym_error</code>, <code>loc_violations</code>, <code>lin_error</code>, <code>neg_weights</code>, "
            "<code>min_eig</code>); hover a cell for the value on each mesh. Tolerances: SYM 1e-10, LIN 1e-9, "
            "PSD −1e-10 (relative). For a non-symmetric operator PSD means every eigenvalue of −W has a "
            "non-negative real part (not that its symmetric part is semi-definite).</p>")


def _uniform_note(df) -> str:
    ok = df[df["status"] == "ok"]
    uni = ok[ok["method"].astype(str).str.contains("uniform|umbrella|graph", regex=True)]
    planar = uni[uni["lin_error"].notna()] if "lin_error" in uni else uni.iloc[0:0]
    parts = ["<div class='note'><b>The uniform (graph) Laplacian.</b> Its weights are symmetric (w<sub>ij</sub> = 1 "
             "for every edge), so SYM holds for W itself; only the normalised form D W with D = diag(1/N<sub>i</sub>) "
             "(the umbrella operator, N<sub>i</sub> the valence) is not symmetric as a matrix. It is local and positive, "
             "but it is not linearly precise: on an irregular planar mesh, W X ≠ 0 at interior vertices, so it fails LIN."]
    if len(planar):
        items = "".join(f"<li>{_esc(r.method)} on {_esc(r.mesh)} ({_esc(noise_label(r.noise_model, r.noise_level))}): "
                        f"lin_error = {_fmt(r.lin_error)}, LIN {_esc(_fmt(r.LIN))}, SYM {_esc(_fmt(r.SYM))}, "
                        f"M⁻¹W symmetric {_esc(_fmt(r.operator_symmetric))}</li>"
                        for r in planar.itertuples(index=False))
        parts.append(f" From this run's planar meshes:<ul>{items}</ul>")
    elif len(uni):
        parts.append(" <i>This run has no planar mesh (LIN is measured only on planar inputs, e.g. "
                     "<code>plane_nondelaunay</code> with noise model <code>none</code>), so the numbers are not shown.</i>")
    else:
        parts.append(" <i>No uniform Laplacian in this run.</i>")
    parts.append("</div>")
    return "".join(parts)


def _all_four_html(df, defaults=None) -> str:
    """Which operators have SYM, LOC, LIN and POS at once on each planar mesh of the run (from the rows)."""
    if "lin_error" not in df or not len(df):
        return ""
    labelled = df.assign(_variant=variant_labels(df, (), defaults))        # from every row, as the tables
    ok = labelled[(labelled["status"] == "ok") & labelled["lin_error"].notna()]
    if not len(ok):
        return ""
    items = []
    for (mesh, nz), g in ok.groupby([ok["mesh"].astype(str), [noise_label(m, lv) for m, lv in
                                                             zip(ok["noise_model"], ok["noise_level"])]]):
        good = g[g["SYM"].astype(bool) & g["LOC"].astype(bool) & g["LIN"].astype(bool) & g["POS"].astype(bool)]
        names = sorted(good["_variant"].unique(), key=natural_key)
        items.append(f"<li><b>{_esc(mesh)}</b> ({_esc(nz)}): "
                     + (_esc(", ".join(names)) if names else "<i>no operator in this run</i>")
                     + f" <span class='muted'>({len(names)} of {g['_variant'].nunique()})</span></li>")
    return ("<p>All four of SYM, LOC, LIN and POS at once, per planar mesh of this run (the only meshes where "
            f"LIN is measured):</p><ul class='allfour'>{''.join(items)}</ul>")


def property_matrix_section(df, spec=None) -> str:
    """HTML of the property matrix, the all-four list and the note on the uniform Laplacian
    (``spec``: the task's declaration from run.json, for the methods' defaults in the labels)."""
    defaults = (spec or {}).get("method_defaults")
    return ("<h3>Property matrix (Wardetzky et al. 2007)</h3>"
            "<p class='theorem'><b>Theorem</b> (Wardetzky, Mathur, Kälberer &amp; Grinspun, <i>Discrete Laplace "
            "operators: no free lunch</i>, SGP 2007): no discrete Laplacian satisfies symmetry (SYM), locality (LOC), "
            "linear precision (LIN) and positive weights (POS) on all triangle meshes. On the plane, the cotangent "
            "weights have all four on Delaunay triangulations without obtuse boundary angles (where they are "
            "non-negative), and the weighted cotangent operator on regular triangulations; PSD follows from SYM "
            "and POS.</p>"
            + _matrix_html(df, defaults) + _all_four_html(df, defaults) + _uniform_note(df))
