/* mesh-shootout report: tables, SVG plots and canvas-2D mesh views drawn from the inline JSON.
   Hand-written, no dependencies, no network. Status markers for tests are written on <body>:
   data-plots-rendered (number of SVG plots drawn), data-view3d (ready | none | failed),
   data-js-error (first uncaught error, if any). */
(function () {
  'use strict';
  var body = document.body;
  window.addEventListener('error', function (e) {
    if (!body.dataset.jsError) body.dataset.jsError = String(e.message || e);
  });
  var D = JSON.parse(document.getElementById('report-data').textContent);
  var SVGNS = 'http://www.w3.org/2000/svg';
  var REF = '#777';
  var plotsRendered = 0;

  // ------------------------------------------------------------------ small helpers
  function el(tag, attrs, kids) {
    var e = document.createElement(tag);
    if (attrs) for (var k in attrs) {
      if (k === 'text') e.textContent = attrs[k];
      else if (k === 'html') e.innerHTML = attrs[k];
      else e.setAttribute(k, attrs[k]);
    }
    (kids || []).forEach(function (c) { if (c) e.appendChild(typeof c === 'string' ? document.createTextNode(c) : c); });
    return e;
  }
  function sv(tag, attrs, text) {
    var e = document.createElementNS(SVGNS, tag);
    for (var k in attrs) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    return e;
  }
  function esc(s) {
    return String(s).replace(/[&<>"']/g, function (c) {
      return {'&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;'}[c];
    });
  }
  function isNum(v) { return typeof v === 'number' && isFinite(v); }
  function fmt(v, d) {
    if (v === null || v === undefined) return '';
    if (typeof v === 'boolean') return v ? 'true' : 'false';
    if (!isNum(v)) return String(v);
    if (Number.isInteger(v) && Math.abs(v) < 1e9) return String(v);
    var a = Math.abs(v);
    d = d || 4;
    if (a === 0) return '0';
    if (a >= 1e-3 && a < 1e6) return String(parseFloat(v.toPrecision(d)));
    return v.toExponential(d - 1).replace('e+', 'e');
  }
  function fmtTime(s) {
    if (!isNum(s)) return '';
    if (s < 1e-3) return fmt(s * 1e6, 3) + ' µs';
    if (s < 1) return fmt(s * 1e3, 3) + ' ms';
    return fmt(s, 3) + ' s';
  }
  // a median time with the spread of its samples: the smallest first and the largest third quartile
  // of the variant's rows in the cell (one row per seed), so a bare median is never the whole story
  function timeCell(t, rows, variant) {
    if (!isNum(t)) return '';
    var own = rows.filter(function (r) { return r._variant === variant; });
    var q1 = own.map(function (r) { return r.time_q1_s; }).filter(isNum);
    var q3 = own.map(function (r) { return r.time_q3_s; }).filter(isNum);
    if (!q1.length || !q3.length) return fmtTime(t);
    return fmtTime(t) + ' <small class="muted" title="interquartile range of the timed samples' +
      (own.length > 1 ? ' (lowest and highest over the seeds)' : '') + '">[' +
      fmtTime(Math.min.apply(null, q1)) + '–' + fmtTime(Math.max.apply(null, q3)) + ']</small>';
  }
  function mean(a) { var s = 0; for (var i = 0; i < a.length; i++) s += a[i]; return s / a.length; }
  function median(a) {
    var b = a.slice().sort(function (x, y) { return x - y; }); var n = b.length;
    return n % 2 ? b[(n - 1) / 2] : (b[n / 2 - 1] + b[n / 2]) / 2;
  }
  function groupBy(rows, keyf) {
    var m = new Map();
    rows.forEach(function (r) { var k = keyf(r); if (!m.has(k)) m.set(k, []); m.get(k).push(r); });
    return m;
  }
  function uniq(a) { return Array.from(new Set(a)); }
  // rows in a fixed cell order (mesh, noise, level, target: numbers by value), not the CSV's, which
  // follows the order the workers finished in, so the winner tables list their cells alike every run
  function inCellOrder(rows) {
    var cmp = function (a, b) { return String(a).localeCompare(String(b), 'en', {numeric: true}); };
    var tgt = function (r) { return isNum(r._target) ? r._target : -1; };
    return rows.slice().sort(function (a, b) {
      return cmp(a.mesh, b.mesh) || cmp(a._noise, b._noise) || (tgt(a) - tgt(b)) || cmp(a._axis || '', b._axis || '');
    });
  }
  function guard(where, host, f) {
    try { return f(); } catch (err) {
      console.error('report: ' + where + ' failed: ' + (err && err.stack || err));
      if (host) host.appendChild(el('div', {'class': 'jserror', text: where + ' failed: ' + err}));
    }
  }

  // ------------------------------------------------------------------ task data
  // colours of a set of names, derived from each name: twenty colours (d3's category10 without its
  // grey, the reference's, then ten picked farthest-first from tab20 and Kelly's colours; every two
  // at least 64 apart in RGB), a name's own the one its FNV-1a hash picks, so a method keeps its
  // colour from report to report; where two names of one set pick the same, the later in sorted
  // order takes the next free one (no two names of a set share a colour); past twenty, each next
  // colour is the one of a grid of hues and lightnesses farthest in RGB from those taken, the
  // reference's grey and white
  var PALETTE = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2', '#bcbd22',
    '#17becf', '#000080', '#dbdb8d', '#a1caf1', '#2b3d26', '#393b79', '#f99379', '#f7b6d2', '#98df8a',
    '#882d17', '#008856', '#f3c300'];
  function hexRgb(h) { return [1, 3, 5].map(function (i) { return parseInt(h.slice(i, i + 2), 16); }); }
  function hslRgb(h, s, l) {
    var a = s * Math.min(l, 1 - l);
    return [0, 8, 4].map(function (n) {
      var k = (n + h / 30) % 12;
      return Math.round(255 * (l - a * Math.max(-1, Math.min(k - 3, 9 - k, 1))));
    });
  }
  function rgbDist(p, q) { return Math.hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]); }
  function nameHash(s) {           // FNV-1a (32 bit) over the name's UTF-16 code units
    var h = 0x811c9dc5;
    for (var i = 0; i < s.length; i++) h = Math.imul(h ^ s.charCodeAt(i), 0x01000193) >>> 0;
    return h;
  }
  function paletteFor(names) {
    var out = {}, taken = PALETTE.map(hexRgb).concat([hexRgb('#777777'), [255, 255, 255]]), grid = [];
    var free = PALETTE.map(function () { return true; }), nfree = PALETTE.length;
    for (var h = 0; h < 360; h += 10) [0.3, 0.45, 0.6].forEach(function (l) { grid.push(hslRgb(h, 0.65, l)); });
    uniq(names).sort().forEach(function (n) {
      if (nfree > 0) {
        var k = nameHash(String(n)) % PALETTE.length;
        while (!free[k]) k = (k + 1) % PALETTE.length;
        free[k] = false;
        nfree -= 1;
        out[n] = PALETTE[k];
        return;
      }
      var best = null, bestD = -1;
      grid.forEach(function (c) {
        var d = Math.min.apply(null, taken.map(function (t) { return rgbDist(c, t); }));
        if (d > bestD) { bestD = d; best = c; }
      });
      taken.push(best);
      out[n] = 'rgb(' + best.join(',') + ')';
    });
    return out;
  }
  function taskRows(task) {
    var T = D.tasks[task];
    if (!T) return null;
    var rows = T.rows.map(function (r) {
      var o = {}; T.columns.forEach(function (c, i) { o[c] = r[i]; }); return o;
    });
    return {T: T, rows: rows, colors: paletteFor(T.variants), variants: T.variants};
  }

  // ------------------------------------------------------------------ plotting (SVG)
  function domain(vals, log, zero) {
    var v = log ? vals.map(Math.log10) : vals.slice();
    var lo = Math.min.apply(null, v), hi = Math.max.apply(null, v);
    if (zero && !log) { lo = Math.min(lo, 0); hi = Math.max(hi, 0); }
    if (hi - lo < 1e-12 * Math.max(1, Math.abs(hi))) {
      var pad = log ? 0.3 : (Math.abs(hi) > 0 ? Math.abs(hi) * 0.2 : 1);
      lo -= pad; hi += pad;
    } else {
      var p = (hi - lo) * 0.07;
      if (!(zero && !log && lo === 0)) lo -= p;
      hi += p;
    }
    return [lo, hi];
  }
  function linTicks(lo, hi) {
    var span = hi - lo, raw = span / 5, mag = Math.pow(10, Math.floor(Math.log10(raw)));
    var step = [1, 2, 2.5, 5, 10].map(function (s) { return s * mag; }).find(function (s) { return span / s <= 6; }) || raw;
    var out = [];
    for (var t = Math.ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step) out.push(Math.abs(t) < step * 1e-9 ? 0 : t);
    return out;
  }
  function ticks(d, log) { // tick positions in axis units (log10 of the value on log axes)
    if (!log) return linTicks(d[0], d[1]);
    if (d[1] - d[0] < 1) {   // less than a decade: evenly spaced values read better than 2-5-10
      var lin = linTicks(Math.pow(10, d[0]), Math.pow(10, d[1])).filter(function (v) { return v > 0; }).map(Math.log10);
      if (lin.length >= 2) return lin;
    }
    var out = [], a = Math.floor(d[0]), b = Math.ceil(d[1]);
    var mult = (d[1] - d[0]) < 2.5 ? [1, 2, 5] : [1];
    var step = (b - a) > 8 ? 2 : 1;
    for (var k = a; k <= b; k += step) mult.forEach(function (m) {
      var t = Math.log10(m) + k; if (t >= d[0] - 1e-9 && t <= d[1] + 1e-9) out.push(t);
    });
    return out;
  }
  function tickLabels(ts, log) { // shortest labels that are all distinct
    var vals = ts.map(function (t) { return log ? Math.pow(10, t) : t; });
    for (var p = 2; p <= 8; p++) {
      var labs = vals.map(function (v) {
        if (v === 0) return '0';
        var a = Math.abs(v);
        if (a >= 1e-3 && a < 1e5) return String(parseFloat(v.toPrecision(p)));
        return v.toExponential(p - 1).replace(/\.?0+e/, 'e').replace('e+', 'e');
      });
      var exact = labs.every(function (l, i) { return Math.abs(parseFloat(l) - vals[i]) <= 1e-9 * Math.abs(vals[i]); });
      if (exact && new Set(labs).size === labs.length) return labs;
    }
    return vals.map(String);
  }
  function okv(v, log) { return isNum(v) && (!log || v > 0); }

  /* spec: {w,h,title,xlabel,ylabel,xlog,ylog,yzero,xdomain,diag,series:[{name,color,pts:[[x,y,tip]],line,dash,ring}],
            front:[[x,y]], hlines:[{y,label}]} */
  function chart(spec) {
    var W = spec.w || 322, H = spec.h || 240;
    var m = {l: 56, r: 12, t: spec.title ? 22 : 10, b: 38};
    var xs = [], ys = [], dropped = 0;
    spec.series.forEach(function (s) {
      s.pts.forEach(function (p) {
        if (okv(p[0], spec.xlog) && okv(p[1], spec.ylog)) { xs.push(p[0]); ys.push(p[1]); } else dropped++;
      });
    });
    (spec.hlines || []).forEach(function (h) { if (okv(h.y, spec.ylog)) ys.push(h.y); });
    var svg = sv('svg', {width: W, height: H, viewBox: '0 0 ' + W + ' ' + H, 'class': 'chart', role: 'img'});
    if (spec.title) svg.appendChild(sv('text', {x: m.l, y: 15, 'font-size': 12, 'font-weight': 600, fill: '#1d2330'}, spec.title));
    if (!xs.length) {
      svg.appendChild(sv('text', {x: W / 2, y: H / 2, 'text-anchor': 'middle', 'font-size': 12, fill: '#888'},
        'no finite' + (spec.ylog || spec.xlog ? ' positive' : '') + ' values to plot'));
      plotsRendered++;
      return svg;
    }
    var xd = spec.xdomain || domain(xs, spec.xlog), yd = domain(ys, spec.ylog, spec.yzero);
    if (spec.diag) { var u = [Math.min(xd[0], yd[0]), Math.max(xd[1], yd[1])]; xd = u; yd = u; }
    function X(v) { var t = spec.xlog ? Math.log10(v) : v; return m.l + (t - xd[0]) / (xd[1] - xd[0]) * (W - m.l - m.r); }
    function Y(v) { var t = spec.ylog ? Math.log10(v) : v; return H - m.b - (t - yd[0]) / (yd[1] - yd[0]) * (H - m.t - m.b); }
    function Xt(t) { return X(spec.xlog ? Math.pow(10, t) : t); }
    function Yt(t) { return Y(spec.ylog ? Math.pow(10, t) : t); }
    var g = sv('g', {});
    svg.appendChild(g);
    g.appendChild(sv('rect', {x: m.l, y: m.t, width: W - m.l - m.r, height: H - m.t - m.b, fill: '#fcfcfd', stroke: '#c9ced8'}));
    var xt = ticks(xd, spec.xlog), xl = tickLabels(xt, spec.xlog);
    xt.forEach(function (t, i) {
      var x = Xt(t);
      g.appendChild(sv('line', {x1: x, x2: x, y1: m.t, y2: H - m.b, stroke: '#eceff4'}));
      g.appendChild(sv('text', {x: x, y: H - m.b + 13, 'text-anchor': 'middle', 'font-size': 10, fill: '#555'}, xl[i]));
    });
    var yt = ticks(yd, spec.ylog), yl = tickLabels(yt, spec.ylog);
    yt.forEach(function (t, i) {
      var y = Yt(t);
      g.appendChild(sv('line', {x1: m.l, x2: W - m.r, y1: y, y2: y, stroke: '#eceff4'}));
      g.appendChild(sv('text', {x: m.l - 4, y: y + 3, 'text-anchor': 'end', 'font-size': 10, fill: '#555'}, yl[i]));
    });
    g.appendChild(sv('text', {x: (m.l + W - m.r) / 2, y: H - 6, 'text-anchor': 'middle', 'font-size': 11, fill: '#333'},
      spec.xlabel + (spec.xlog ? ' (log)' : '')));
    g.appendChild(sv('text', {x: 12, y: (m.t + H - m.b) / 2, 'text-anchor': 'middle', 'font-size': 11, fill: '#333',
      transform: 'rotate(-90 12 ' + (m.t + H - m.b) / 2 + ')'}, spec.ylabel + (spec.ylog ? ' (log)' : '')));
    var clip = 'c' + Math.random().toString(36).slice(2);
    var defs = sv('defs', {}); var cp = sv('clipPath', {id: clip});
    cp.appendChild(sv('rect', {x: m.l, y: m.t, width: W - m.l - m.r, height: H - m.t - m.b}));
    defs.appendChild(cp); svg.appendChild(defs);
    var inner = sv('g', {'clip-path': 'url(#' + clip + ')'});
    svg.appendChild(inner);
    if (spec.diag) {
      var a = Math.pow(10, xd[0]), b = Math.pow(10, xd[1]);
      if (!spec.xlog) { a = xd[0]; b = xd[1]; }
      inner.appendChild(sv('line', {x1: X(a), y1: Y(a), x2: X(b), y2: Y(b), stroke: REF, 'stroke-dasharray': '5 4'}));
    }
    (spec.hlines || []).forEach(function (h) {
      if (!okv(h.y, spec.ylog)) return;
      inner.appendChild(sv('line', {x1: m.l, x2: W - m.r, y1: Y(h.y), y2: Y(h.y), stroke: REF, 'stroke-dasharray': '5 4'}));
      inner.appendChild(sv('text', {x: W - m.r - 3, y: Y(h.y) - 3, 'text-anchor': 'end', 'font-size': 10, fill: '#555'}, h.label));
    });
    if (spec.front && spec.front.length > 1) {
      var d = '', f = spec.front;
      for (var i = 0; i < f.length; i++) {
        d += (i ? 'H' + X(f[i][0]).toFixed(1) + 'V' : 'M' + X(f[i][0]).toFixed(1) + ',') + Y(f[i][1]).toFixed(1);
      }
      inner.appendChild(sv('path', {d: d, fill: 'none', stroke: '#222', 'stroke-width': 1.2, 'stroke-dasharray': '3 3'}));
    }
    spec.series.forEach(function (s) {
      var pts = s.pts.filter(function (p) { return okv(p[0], spec.xlog) && okv(p[1], spec.ylog); });
      if (s.line && pts.length > 1) {
        inner.appendChild(sv('polyline', {points: pts.map(function (p) { return X(p[0]).toFixed(1) + ',' + Y(p[1]).toFixed(1); }).join(' '),
          fill: 'none', stroke: s.color, 'stroke-width': s.width || 1.6, 'stroke-dasharray': s.dash || ''}));
      }
      if (s.marker === false) return;
      pts.forEach(function (p) {
        var c = sv('circle', {cx: X(p[0]).toFixed(1), cy: Y(p[1]).toFixed(1), r: s.r || 4, fill: s.color,
          stroke: p[3] ? '#111' : '#fff', 'stroke-width': p[3] ? 1.8 : 0.8, 'class': 'pt'});
        if (p[2]) c.appendChild(sv('title', {}, p[2]));
        inner.appendChild(c);
      });
    });
    if (dropped && spec.noteDropped !== false) {
      svg.appendChild(sv('text', {x: W - m.r, y: 15, 'text-anchor': 'end', 'font-size': 9, fill: '#999'},
        dropped + ' point' + (dropped > 1 ? 's' : '') + (spec.ylog || spec.xlog ? ' ≤ 0 or' : '') + ' blank not shown'));
    }
    plotsRendered++;
    return svg;
  }
  // pts [[time, value, tip, n, variant]] of one panel (rows rs, metric key, lower is better): the
  // points no other point dominates, sorted by time. q dominates p when q is faster beyond the timing
  // noise (`timeTiedWith` tells them apart, as the fastest's ties) and not less accurate beyond the
  // metric's tolerance, or not slower beyond the noise and more accurate beyond the tolerance (as the
  // winners' ties: `ties` of the means and beaten on every seed). Points that tie both ways stay both.
  function pareto(pts, tol, rs, key) {
    var s = pts.filter(function (p) { return isNum(p[0]) && isNum(p[1]); })
      .slice().sort(function (a, b) { return a[0] - b[0] || a[1] - b[1]; });
    var faster = function (q, p) { return q[0] < p[0] && !timeTiedWith(rs, q[4], p[4]); };
    var better = function (q, p) {
      return q[1] < p[1] && !ties(p[1], q[1], tol, bracketTop(rs, q[4], key, tol, true)) &&
        beatenOnEverySeed(rs, q[4], p[4], key, tol, true);
    };
    return s.filter(function (p) {
      return !s.some(function (q) {
        return q !== p && ((faster(q, p) && !better(p, q)) || (!faster(p, q) && better(q, p)));
      });
    });
  }
  // the compare tolerance the task declares for a metric (as the leaderboard and winners.csv use it):
  // a value within max(rel * |best|, abs) of the best ties with it
  // ([2], [3]: a sampled metric's standard-error column and how many combined standard errors tie on a seed)
  // ([4]: a certified bound's bracket upper-end column, e.g. hausdorff_upper for hausdorff)
  // ([5], [6]: the standard-error column printed as the value's ±, and whether its sample is one every
  // variant and seed of a cell shares (se_shared: then [2] is empty, as ties on a shared sample are paired))
  function tolOf(spec, key) {
    var m = ((spec || {}).metrics || []).filter(function (x) { return x.name === key; })[0];
    var shared = !!(m && m.se_shared === true);
    return [m && isNum(m.rel) ? m.rel : 0.01, m && isNum(m.abs) ? m.abs : 0, (m && !shared && m.se) || '',
      m && isNum(m.se_z) ? m.se_z : 3, (m && m.better === 'lower' && m.upper) || '', (m && m.se) || '', shared];
  }
  // a ties with best; with reach (best's bracket upper end, `bracketTop`), when a lies within the
  // tolerance of it: brackets that overlap tie, as compare and winners.csv judge them
  function ties(a, best, tol, reach) {
    var t = Math.max(tol[0] * Math.abs(best), tol[1]);
    return Math.abs(a - best) <= t || (isNum(reach) && a - reach <= t);
  }
  // a row's bracket upper end: its tol[4] column where that is a number at or above the value, else the value
  function rowTop(r, key, tol) {
    var u = tol[4] ? r[tol[4]] : null;
    return isNum(u) && u >= r[key] ? u : r[key];
  }
  // the mean upper end of variant v's brackets over rows (a lower-is-better certified bound), else undefined
  function bracketTop(rows, v, key, tol, lower) {
    if (!lower || !tol[4]) return undefined;
    var xs = rows.filter(function (r) { return r._variant === v && isNum(r[key]); }).map(function (r) { return rowTop(r, key, tol); });
    return xs.length ? mean(xs) : undefined;
  }
  // variant v's mean value over a cell's rows as printed (d significant digits): [lower, upper] for a
  // certified bound whose mean bracket ends differ at those digits (tol[4], e.g. hausdorff_upper), the
  // value ± the standard error of the mean over seeds, sqrt(sum se^2) / n, for a sampled metric
  // (tol[5]; over a shared sample, tol[6], the mean of the seeds' errors), else the value; as winners.md prints it
  function valueText(rows, v, key, tol, d) {
    var rs = rows.filter(function (r) { return r._variant === v && isNum(r[key]); });
    if (!rs.length) return '';
    var txt = fmt(mean(rs.map(function (r) { return r[key]; })), d);
    var up = bracketTop(rows, v, key, tol, true);
    if (isNum(up) && fmt(up, d) !== txt) return '[' + txt + ', ' + fmt(up, d) + ']';
    var es = tol[5] ? rs.map(function (r) { return r[tol[5]]; }) : [];
    if (es.length && es.every(isNum)) {
      return txt + ' ± ' + fmt(tol[6] ? mean(es) : Math.sqrt(es.reduce(function (a, e) { return a + e * e; }, 0)) / es.length, 2);
    }
    return txt;
  }
  // the caption under a best table for a bracketed or sampled metric, as winners.md words it
  function valueNote(key, tol) {
    if (tol[4]) return el('p', {'class': 'caption', text: key + ': the lower end of a certified bracket; [lower, upper] ' +
      'where the two differ at 4 digits (means over seeds).'});
    if (tol[6]) return el('p', {'class': 'caption', text: key + ': ± its standard error over the sample every method of the ' +
      'cell shares (e.g. the sources: another sample could move the values; the methods compare on this one, so ties ' +
      'ignore it), over seeds the mean of theirs.'});
    if (tol[5]) return el('p', {'class': 'caption', text: key + ': a sampled estimate ± its standard error (of the mean over seeds).'});
    return el('span');
  }
  // with several seeds, a variant ties with the best unless the best is better beyond the tolerance on
  // every seed both have (as winners.csv); rows: the cell's rows, one per variant and seed
  // (a sampled metric: the tolerance on a seed is at least se_z times the two values' combined standard error)
  // (a certified bound: v's lower end must lie beyond best's bracket upper end on the seed)
  function beatenOnEverySeed(rows, best, v, key, tol, lower) {
    var a = new Map(), b = new Map(), n = 0, all = true, se = tol[2];
    var add = function (m, s, x, e, up) {              // mean per seed, of the value, its standard error and upper end
      var c = m.get(s) || [0, 0, 0, 0, 0]; c[0] += x; c[1]++; c[4] += up;
      if (isNum(e)) { c[2] += e; c[3]++; }
      m.set(s, c);
    };
    rows.forEach(function (r) {
      if (!isNum(r[key])) return;
      var s = r.seed === undefined || r.seed === null ? '' : String(r.seed);
      var e = se ? r[se] : null;
      if (r._variant === best) add(a, s, r[key], e, rowTop(r, key, tol));
      else if (r._variant === v) add(b, s, r[key], e, r[key]);
    });
    a.forEach(function (ca, s) {
      if (!b.has(s)) return;
      n++;
      var va = ca[0] / ca[1], cb = b.get(s), vb = cb[0] / cb[1];
      var gap = lower ? vb - (tol[4] ? ca[4] / ca[1] : va) : va - vb;
      var t = Math.max(tol[0] * Math.abs(va), tol[1]);
      if (se && ca[3] && cb[3]) t = Math.max(t, tol[3] * Math.hypot(ca[2] / ca[3], cb[2] / cb[3]));
      if (!(gap > t)) all = false;
    });
    return n === 0 || all;
  }
  // the variants whose time is not told apart from the fastest's: on some seed they share, the
  // fastest's interquartile range reaches the other's, or its median is less than 10% lower (the
  // spread between two runs of the same code on a shared machine); no shared seed: tied
  var TIME_GAP = 1.1;
  function timeTiedWith(rows, fast, v) {
    var a = new Map(), b = new Map(), n = 0, apart = true;
    rows.forEach(function (r) {
      if (!isNum(r.time_s)) return;
      var s = r.seed === undefined || r.seed === null ? '' : String(r.seed);
      if (r._variant === fast) a.set(s, r); else if (r._variant === v) b.set(s, r);
    });
    a.forEach(function (ra, s) {
      var rb = b.get(s);
      if (!rb) return;
      n++;
      var q3 = isNum(ra.time_q3_s) ? ra.time_q3_s : ra.time_s, q1 = isNum(rb.time_q1_s) ? rb.time_q1_s : rb.time_s;
      if (!(q3 < q1 && rb.time_s >= TIME_GAP * ra.time_s)) apart = false;
    });
    return n === 0 || !apart;
  }
  // the variants of a cell that can win, as in winners.csv: every row of the variant in the cell has a
  // value and, unless invalid results are shown, none is invalid (one failed, diverged or invalid seed
  // takes the variant out of the cell: no mean over the seeds that happen to be good)
  function cellVariants(cell, key) {
    var keep = new Set();
    var seedOf = function (r) { return String(r.seed); };
    var nSeeds = new Set(cell.map(seedOf)).size;      // a variant without a row on some seed of the cell: blank, as winners.csv
    groupBy(cell, function (r) { return r._variant; }).forEach(function (g, v) {
      var blank = new Set(g.map(seedOf)).size < nSeeds ||
        g.some(function (r) { return r.status !== 'ok' || r.diverged || r._missing || !isNum(r[key]); });   // _missing: no measurement, shown invalid or not
      if (!blank && (showInvalid || !g.some(function (r) { return r._invalid; }))) keep.add(v);
    });
    return keep;
  }
  // the rows of a cell's variants that can win (`cellVariants`) among the shown ones (visSet); when no
  // result of the cell is valid, a row of table bt says so (ncol cells after mesh, noise [and target])
  function winnerRows(cell, key, visSet, bt, ncol, target) {
    var keep = cellVariants(cell, key);
    if (!keep.size) {
      var bad = cell.filter(function (r) { return r._invalid && r.status !== 'unavailable' && r.status !== 'not run'; });   // missing, as in winners.csv
      var valid = cell.filter(function (r) { return r.status === 'ok' && !r._invalid && !r._missing; });
      var applies = !valid.length || valid.some(function (r) { return isNum(r[key]); });   // as winners.csv: the metric applies here
      if (bad.length && applies) bt.appendChild(noValidRow(bad, ncol, target));
      return [];
    }
    return cell.filter(function (r) { return keep.has(r._variant) && visSet.has(r); });
  }
  // the best item by value (lower or higher), the alphabetically first name on an exact tie, as winners.csv
  function pickBest(items, valueOf, nameOf, lower) {
    return items.reduce(function (a, b) {
      var va = valueOf(a), vb = valueOf(b);
      return (lower ? vb < va : vb > va) || (vb === va && nameOf(b) < nameOf(a)) ? b : a;
    });
  }
  // the names of items tied with best: within the tolerance of its mean, or not beaten on every seed
  function tiedWith(items, best, valueOf, nameOf, rows, key, tol, lower) {
    return items.filter(function (x) {
      return x !== best && (ties(valueOf(x), valueOf(best), tol, bracketTop(rows, nameOf(best), key, tol, lower)) ||
        !beatenOnEverySeed(rows, nameOf(best), nameOf(x), key, tol, lower));
    }).map(nameOf);
  }
  function tiedNote(names) { // ' (tied: a, b)', or ' (tied: 5 others)' with the names on hover
    if (!names.length) return '';
    return ' <span class="muted" title="within the metric\'s tolerance of the best, or not beaten on every seed ' +
      '(a sampled metric: beyond 3 combined standard errors): ' +
      esc(names.join(', ')) +
      '">(tied: ' + (names.length <= 2 ? esc(names.join(', ')) : names.length + ' others') + ')</span>';
  }
  function timeTiedNote(names) { // ' (tied: a)': times the samples do not tell apart from the fastest
    if (!names.length) return '';
    return ' <span class="muted" title="not told apart from the fastest: on some seed the interquartile ranges ' +
      'of the samples overlap or the medians are less than 10% apart: ' + esc(names.join(', ')) +
      '">(tied: ' + (names.length <= 2 ? esc(names.join(', ')) : names.length + ' others') + ')</span>';
  }
  function noValidRow(rs, ncol, target) { // a cell whose every result is invalid: said, not left out
    return el('tr', {html: '<td>' + esc(rs[0].mesh) + '</td><td>' + esc(rs[0]._noise) + '</td>' +
      (target === undefined ? '' : '<td>' + esc(fmt(target)) + '</td>') + '<td colspan="' + ncol +
      '" class="muted">no valid result (' + uniq(rs.map(function (r) { return r._variant; })).length + ' invalid: ' +
      esc(uniq(rs.map(function (r) { return r._invalid; })).join('; ')) +
      ')</td>'});
  }
  function staticLegend(names, colorFor) { // a legend that only names the drawn lines (no toggling)
    var box = el('div', {'class': 'legend'});
    names.forEach(function (name) {
      box.appendChild(el('span', {style: 'cursor:default'}, [el('i', {style: 'background:' + colorFor(name)}), name]));
    });
    return box;
  }
  function legend(variants, colors, hidden, onToggle, extra) {
    var box = el('div', {'class': 'legend'});
    variants.forEach(function (v) {
      var s = el('span', {title: 'click to hide/show'}, [el('i', {style: 'background:' + colors[v]}), v]);
      if (hidden.has(v)) s.className = 'off';
      s.addEventListener('click', function () { if (hidden.has(v)) hidden.delete(v); else hidden.add(v); onToggle(); });
      box.appendChild(s);
    });
    (extra || []).forEach(function (x) {
      var icon = x === 'Pareto front' ? el('i', {'class': 'ref front'}) : el('i', {'class': 'ref'});
      box.appendChild(el('span', {style: 'cursor:default'}, [icon, x]));
    });
    return box;
  }
  function panelGroup(parent, title, caption, leg) {
    var g = el('div', {'class': 'plotgroup'}, [el('h4', {text: title})]);
    if (caption) g.appendChild(el('p', {'class': 'caption', html: caption}));
    if (leg) g.appendChild(leg());
    var panels = el('div', {'class': 'panels'});
    g.appendChild(panels);
    parent.appendChild(g);
    return panels;
  }
  function addPanel(panels, svg) {
    var p = el('div', {'class': 'panel'});
    p.appendChild(svg);
    p.appendChild(svgDownload(svg));
    panels.appendChild(p);
  }
  // every plot downloads as a standalone SVG file (made in the page: nothing is fetched)
  function svgDownload(svg) {
    var a = el('a', {'class': 'svgdl', href: '#', text: 'SVG', title: 'download this plot as SVG'});
    a.addEventListener('click', function (e) {
      e.preventDefault();
      var clone = svg.cloneNode(true);
      clone.setAttribute('xmlns', SVGNS);
      var text = '<?xml version="1.0" encoding="UTF-8"?>\n' + new XMLSerializer().serializeToString(clone);
      var url = URL.createObjectURL(new Blob([text], {type: 'image/svg+xml'}));
      var d = el('a', {href: url, download: (svg.getAttribute('data-name') || 'plot') + '.svg'});
      document.body.appendChild(d); d.click(); d.remove();
      setTimeout(function () { URL.revokeObjectURL(url); }, 1000);
    });
    return a;
  }
  function autoLog(vals) {
    var v = vals.filter(isNum);
    if (!v.length || Math.min.apply(null, v) <= 0) return false;
    return Math.max.apply(null, v) / Math.min.apply(null, v) > 20;
  }
  function tipOf(r, extra, group) {   // group: the rows a point aggregates (several seeds: no one seed or case named)
    var many = group && group.length > 1;
    return r._variant + '\n' + r.mesh + ', ' + r._noise +
      (many ? ', seeds ' + group.map(function (x) { return x.seed; }).join(', ')
            : (r.seed !== null && r.seed !== undefined ? ', seed ' + r.seed : '')) +
      '\n' + extra + (many ? '\ncases ' + group.map(function (x) { return x.case_id; }).join(', ') : '\ncase ' + r.case_id);
  }
  function histPlot(parent, d, hidden, title, mkLeg) {
    var rows = d.rows.filter(function (r) { return r.status === 'ok' && Array.isArray(r._hist); });
    if (!rows.length) return;
    var panels = panelGroup(parent, title, 'Per-face minimum angle, 5° bins over [0°, 60°], summed over all ok cases ' +
      'of each method and shown as the fraction of faces. Mass to the right is better (60° = equilateral); ' +
      'faces under 10° are slivers.', mkLeg);
    var series = [];
    groupBy(rows, function (r) { return r._variant; }).forEach(function (rs, v) {
      if (hidden.has(v)) return;
      var sum = null;
      rs.forEach(function (r) { if (!sum) sum = r._hist.map(function () { return 0; }); r._hist.forEach(function (c, i) { sum[i] += c; }); });
      var tot = sum.reduce(function (a, b) { return a + b; }, 0) || 1;
      series.push({name: v, color: d.colors[v], line: true, r: 3, pts: sum.map(function (c, i) {
        return [i * 5 + 2.5, c / tot, v + '\n' + (i * 5) + '–' + (i * 5 + 5) + '°: ' + fmt(100 * c / tot, 3) + ' % of ' + tot + ' faces'];
      })});
    });
    addPanel(panels, chart({w: 560, h: 280, xlabel: 'per-face minimum angle (degrees)', ylabel: 'fraction of faces',
      xdomain: [0, 60], yzero: true, series: series}));
  }

  // ------------------------------------------------------------------ tables
  var BOOL_COLS = {SYM: 1, LOC: 1, LIN: 1, POS: 1, psd: 1, operator_symmetric: 1, manifold: 1, topology_changed: 1, diverged: 1};
  function paramText(p) {
    try { var o = JSON.parse(p); return Object.keys(o).filter(function (k) { return o[k] !== null; })
      .map(function (k) { return k + '=' + (typeof o[k] === 'object' ? JSON.stringify(o[k]) : o[k]); }).join(', '); }
    catch (e) { return p || ''; }
  }
  function rowsTable(task, d) {
    var host = document.getElementById('rows-' + task);
    var cols = d.T.columns.filter(function (c) { return c[0] !== '_' && c !== 'task' && c !== 'min_angle_hist'; });
    var state = {col: null, dir: 1, q: '', status: ''};
    var statuses = uniq(d.rows.map(function (r) { return r.status; }));
    var search = el('input', {type: 'search', placeholder: 'filter: words that must all appear in a row', size: 42});
    var sel = el('select', {}, [el('option', {value: '', text: 'any status'})].concat(statuses.map(function (s) {
      return el('option', {value: s, text: s}); })));
    var count = el('span', {'class': 'muted'});
    host.appendChild(el('div', {'class': 'controls'}, [search, sel, count,
      el('span', {'class': 'muted', text: 'click a column header to sort'})]));
    var wrap = el('div', {'class': 'tablewrap'});
    var table = el('table', {'class': 'rowtable'});
    var thead = el('thead'), tbody = el('tbody');
    table.appendChild(thead); table.appendChild(tbody); wrap.appendChild(table); host.appendChild(wrap);
    var texts = d.rows.map(function (r) {
      return cols.map(function (c) { return c === 'params' ? paramText(r[c]) : fmt(r[c]); }).join(' ').toLowerCase();
    });
    var badWhenTrue = {topology_changed: 1, diverged: 1};
    ((d.T.spec || {}).metrics || []).forEach(function (m) { if (m.better === 'false') badWhenTrue[m.name] = 1; });
    function cell(r, c) {
      var v = r[c];
      if (v === null || v === undefined || v === '') return '<td></td>';
      if (c === 'params') return '<td>' + esc(paramText(v)) + '</td>';
      if (c === 'status') return '<td class="st-' + esc(v) + '">' + esc(v) + '</td>';
      if (c === 'error') return '<td class="err" title="' + esc(v) + '">' + esc(v) + '</td>';
      if (c === 'case_id') return '<td class="mono">' + esc(v) + '</td>';
      if (typeof v === 'boolean' || BOOL_COLS[c]) {
        var good = badWhenTrue[c] ? !v : v;          // the metric's declared direction (better: false)
        return '<td class="' + (good ? 't' : 'f') + '">' + (v ? '✓' : '✗') + '</td>';
      }
      if (isNum(v)) return '<td class="num" title="' + v + '">' + (c.indexOf('time') === 0 ? fmtTime(v) : fmt(v)) + '</td>';
      return '<td>' + esc(v) + '</td>';
    }
    function render() {
      thead.innerHTML = '<tr>' + cols.map(function (c) {
        var mark = state.col === c ? (state.dir > 0 ? ' ▲' : ' ▼') : '';
        return '<th data-col="' + esc(c) + '"' + (state.col === c ? ' class="sorted"' : '') + '>' + esc(c) + mark + '</th>';
      }).join('') + '</tr>';
      var words = state.q.toLowerCase().split(/\s+/).filter(Boolean);
      var idx = [];
      d.rows.forEach(function (r, i) {
        if (state.status && r.status !== state.status) return;
        for (var w = 0; w < words.length; w++) if (texts[i].indexOf(words[w]) < 0) return;
        idx.push(i);
      });
      if (state.col) {
        var c = state.col;
        idx.sort(function (a, b) {
          var x = d.rows[a][c], y = d.rows[b][c];
          var xn = x === null || x === undefined || x === '', yn = y === null || y === undefined || y === '';
          if (xn || yn) return xn === yn ? 0 : (xn ? 1 : -1);
          if (typeof x === 'number' && typeof y === 'number') return (x - y) * state.dir;
          return String(x).localeCompare(String(y)) * state.dir;
        });
      }
      var LIMIT = 2000;
      tbody.innerHTML = idx.slice(0, LIMIT).map(function (i) {
        var r = d.rows[i]; return '<tr>' + cols.map(function (c) { return cell(r, c); }).join('') + '</tr>';
      }).join('');
      count.textContent = idx.length + ' of ' + d.rows.length + ' rows' + (idx.length > LIMIT ? ' (first ' + LIMIT + ' shown)' : '');
    }
    thead.addEventListener('click', function (e) {
      var th = e.target.closest('th'); if (!th) return;
      var c = th.getAttribute('data-col');
      if (state.col === c) state.dir = -state.dir; else { state.col = c; state.dir = 1; }
      render();
    });
    search.addEventListener('input', function () { state.q = search.value; render(); });
    sel.addEventListener('change', function () { state.status = sel.value; render(); });
    render();
    RERENDER.push(render);
  }

  // ------------------------------------------------------------------ sections
  function selectEl(options, value, onChange) {
    var s = el('select', {}, options.map(function (o) { return el('option', {value: o[0], text: o[1]}); }));
    s.value = value;
    s.addEventListener('change', function () { onChange(s.value); });
    return s;
  }
  function meshFilter(rows, state, rerender) {
    var meshes = uniq(rows.map(function (r) { return r.mesh; }));
    if (meshes.length < 2) return null;
    return el('label', {}, ['mesh ', selectEl([['', 'all meshes']].concat(meshes.map(function (m) { return [m, m]; })), '',
      function (v) { state.mesh = v; rerender(); })]);
  }

  function laplacianSection(d) {
    var host = document.getElementById('plots-laplacian');
    var hidden = new Set();
    var leg = el('div'), plots = el('div');
    host.appendChild(leg); host.appendChild(plots);
    function render() {
      leg.innerHTML = ''; plots.innerHTML = '';
      var mkLeg = function () { return legend(d.variants, d.colors, hidden, render); };
      var ok = d.rows.filter(function (r) { return r.status === 'ok' && isNum(r.time_s); });
      var panels = panelGroup(plots, 'Time to build the operator vs mesh size',
        'Median of the repeats; each point is one mesh and noise level (median over seeds). Hover a point for details.', mkLeg);
      var series = [];
      groupBy(ok, function (r) { return r._variant; }).forEach(function (rs, v) {
        if (hidden.has(v)) return;
        var pts = [];
        groupBy(rs, function (r) { return r.mesh + '|' + r._noise; }).forEach(function (g) {
          var r = g[0], t = median(g.map(function (x) { return x.time_s; }));
          pts.push([r.n_vertices, t, tipOf(r, 'time ' + fmtTime(t) + ', ' + r.n_vertices + ' vertices')]);
        });
        pts.sort(function (a, b) { return a[0] - b[0]; });
        series.push({name: v, color: d.colors[v], pts: pts, line: true, width: 1.1, r: 3.5});
      });
      addPanel(panels, chart({w: 560, h: 300, xlabel: 'vertices', ylabel: 'time (s)', xlog: true, ylog: true, series: series}));
    }
    render();
    RERENDER.push(render);
  }

  var SMOOTH_METRICS = [
    ['dist_mean', 'mean distance to the clean surface', 'input_dist_mean'],
    ['dist_mean_sym', 'two-sided mean: of dist_mean and dist_mean_back', 'input_dist_mean_sym'],
    ['dist_mean_back', 'mean distance of the clean vertices to the result', null],
    ['ev_mean', 'mean vertex error (to its own clean vertex)', 'input_ev_mean'],
    ['ev_rms', 'RMS vertex error', null],
    ['ev_sun', 'E_v, Sun et al. 2007 (area-weighted RMS distance)', null],
    ['hausdorff', 'Hausdorff distance to the clean surface', null],
    ['normal_error_deg', 'mean face-normal error (degrees)', 'input_normal_error_deg'],
    ['normal_error_rms_deg', 'RMS face-normal error (degrees)', null]];

  function smoothingSection(d) {
    var host = document.getElementById('plots-smoothing');
    var state = {metric: 'dist_mean', mesh: ''};
    var hidden = new Set();
    var controls = el('div', {'class': 'controls'});
    var leg = el('div'), plots = el('div');
    host.appendChild(controls); host.appendChild(leg); host.appendChild(plots);
    controls.appendChild(el('label', {}, ['accuracy metric ', selectEl(SMOOTH_METRICS.map(function (m) {
      return [m[0], m[0] + ' — ' + m[1]]; }), state.metric, function (v) { state.metric = v; render(); })]));
    var mf = meshFilter(d.rows, state, function () { render(); });
    if (mf) controls.appendChild(mf);
    function render() {
      leg.innerHTML = ''; plots.innerHTML = '';
      var M = SMOOTH_METRICS.find(function (m) { return m[0] === state.metric; });
      var key = M[0], inKey = M[2], label = key + (key.indexOf('deg') > 0 ? ' (degrees)' : ' (/ bbox diagonal)');
      var mkLeg = function (extra) { return function () { return legend(d.variants, d.colors, hidden, render, extra); }; };
      var all = d.rows.filter(function (r) { return !state.mesh || r.mesh === state.mesh; });
      var ok = all.filter(function (r) { return r.status === 'ok' && !r.diverged; });
      var nDiv = all.filter(function (r) { return r.diverged; }).length;
      if (nDiv) plots.appendChild(el('p', {'class': 'warn', text: nDiv + ' diverged result(s) (non-finite or exploded coordinates) are not plotted; see the table.'}));
      var vis = ok.filter(function (r) { return !hidden.has(r._variant) && isNum(r[key]); });
      var panelsKey = function (r) { return r.mesh + ' · ' + r._noise; };

      // best per mesh and noise level
      var bt = el('table', {'class': 'best'});
      bt.innerHTML = '<tr><th>mesh</th><th>noise</th><th>most accurate</th><th>' + esc(key) + '</th><th>noisy input</th>' +
        '<th>time</th><th>Pareto front (fastest first): method, ' + esc(key) + ', time</th></tr>';
      var anyWorse = false;
      var nInvalid = vis.filter(function (r) { return r._invalid; }).length;
      var tol = tolOf(d.T.spec, key), visSet = new Set(vis);
      groupBy(inCellOrder(all), panelsKey).forEach(function (cell) {   // every row of the cell: failed, diverged and hidden too
        var rs = winnerRows(cell, key, visSet, bt, 5);
        if (!rs.length) return;
        var pts = aggregate(rs, key);
        var best = pickBest(pts, function (p) { return p[1]; }, function (p) { return p[4]; }, true);
        var tied = tiedWith(pts, best, function (p) { return p[1]; }, function (p) { return p[4]; }, rs, key, tol, true);
        var inp = inKey ? mean(rs.map(function (r) { return r[inKey]; }).filter(isNum)) : null;
        if (isNum(inp) && best[1] > inp) anyWorse = true;
        var front = pareto(pts, tol, rs, key).map(function (p) { return esc(p[4]) + ' ' + fmt(p[1], 3) + ', ' + timeCell(p[0], rs, p[4]); }).join('<br>');
        var tr = el('tr', {html: '<td>' + esc(rs[0].mesh) + '</td><td>' + esc(rs[0]._noise) + '</td><td><i style="color:' +
          d.colors[best[4]] + '">●</i> ' + esc(best[4]) + tiedNote(tied) + '</td><td class="num' +
          (isNum(inp) && best[1] > inp ? ' worse" title="worse than the noisy input' : '') + '">' + valueText(rs, best[4], key, tol, 4) + '</td><td class="num">' +
          (isNum(inp) ? fmt(inp, 4) : '—') + '</td><td class="num">' + timeCell(best[0], rs, best[4]) + '</td><td>' + front + '</td>'});
        bt.appendChild(tr);
      });
      plots.appendChild(el('h4', {text: 'Most accurate method per mesh and noise level'}));
      plots.appendChild(bt);
      plots.appendChild(valueNote(key, tol));
      plots.appendChild(invalidNote(nInvalid));
      if (anyWorse) plots.appendChild(el('p', {'class': 'caption', html: 'Red: even the most accurate method left the mesh ' +
        'further from the clean one than the noisy input was (by ' + esc(key) + ').'}));

      // accuracy vs time
      var panels = panelGroup(plots, 'Accuracy vs time, per mesh and noise level',
        'x: median time of the method call (log); y: ' + esc(key) + ' (mean over seeds). Black-ringed points and the dashed ' +
        'staircase are the Pareto front: no other method in the panel is faster beyond the timing noise and not less ' +
        'accurate, or not slower and more accurate beyond the metric\'s tolerance (as the winner tables tie them; ' +
        'times are told apart as the fastest\'s ties are). ' + (showInvalid ? '' : 'Invalid results are not plotted. ') +
        (inKey ? 'The grey dashed line is the noisy input: points above it made the mesh worse.' : ''),
        mkLeg(inKey ? ['noisy input', 'Pareto front'] : ['Pareto front']));
      groupBy(vis.filter(validOrShown), panelsKey).forEach(function (rs, title) {
        var pts = aggregate(rs, key), front = pareto(pts, tol, rs, key);
        var onFront = new Set(front);
        var series = [];
        groupBy(pts, function (p) { return p[4]; }).forEach(function (ps, v) {
          series.push({name: v, color: d.colors[v], pts: ps.map(function (p) { return [p[0], p[1], p[2], onFront.has(p)]; })});
        });
        var inp = inKey ? mean(rs.map(function (r) { return r[inKey]; }).filter(isNum)) : null;
        addPanel(panels, chart({title: title, xlabel: 'time (s)', ylabel: label, xlog: true,
          ylog: autoLog(pts.map(function (p) { return p[1]; }).concat(isNum(inp) ? [inp] : [])),
          series: series, front: front, hlines: isNum(inp) ? [{y: inp, label: 'noisy input'}] : []}));
      });

      // error vs noise level
      var levels = uniq(vis.map(function (r) { return r.noise_level; }).filter(isNum));
      var enPanels = levels.length > 1 ? panelGroup(plots, 'Error vs noise level, per mesh and noise model',
        'Mean over seeds; noise level = σ / mean edge length.' + (inKey ? ' Grey dashed: the noisy input.' : '') +
        (showInvalid ? '' : ' Invalid results are not plotted.'),
        mkLeg(inKey ? ['noisy input'] : [])) : null;       // a single level: no line to draw
      var byMeshModel = function (r) { return r.mesh + ' · ' + r.noise_model; };
      var allOf = groupBy(vis, byMeshModel);        // the noisy input's line: its value does not depend on validity
      groupBy(levels.length > 1 ? vis.filter(validOrShown) : [], byMeshModel).forEach(function (rs, title) {
        var series = [];
        var yall = [];
        groupBy(rs, function (r) { return r._variant; }).forEach(function (vr, v) {
          var pts = [];
          groupBy(vr, function (r) { return r.noise_level; }).forEach(function (g, lv) {
            var y = mean(g.map(function (r) { return r[key]; }));
            yall.push(y);
            pts.push([lv, y, v + '\n' + title + ' ' + lv + '\n' + key + ' ' + fmt(y) + ' (' + g.length + ' case' + (g.length > 1 ? 's' : '') + ')']);
          });
          pts.sort(function (a, b) { return a[0] - b[0]; });
          series.push({name: v, color: d.colors[v], pts: pts, line: true});
        });
        if (inKey) {
          var ip = [];
          groupBy(allOf.get(title), function (r) { return r.noise_level; }).forEach(function (g, lv) {
            var y = mean(g.map(function (r) { return r[inKey]; }).filter(isNum)); yall.push(y);
            ip.push([lv, y, 'noisy input at ' + lv + ': ' + fmt(y)]);
          });
          ip.sort(function (a, b) { return a[0] - b[0]; });
          series.unshift({name: 'noisy input', color: REF, pts: ip, line: true, dash: '5 4', r: 2.5});
        }
        addPanel(enPanels, chart({title: title, xlabel: 'noise level', ylabel: label, ylog: autoLog(yall), series: series}));
      });

      // input vs output
      var ioKey = inKey ? key : 'dist_mean', ioIn = inKey || 'input_dist_mean';
      var ioPanels = panelGroup(plots, 'Input error vs output error (improvement)',
        'Each point is one case. Below the dashed diagonal y = x the method reduced the error of its noisy input; ' +
        'above it, it made things worse.' + (inKey ? '' : ' (' + esc(key) + ' has no input counterpart; showing dist_mean.)'),
        mkLeg([]));
      var ioSeries = [];
      groupBy(ok.filter(function (r) { return !hidden.has(r._variant) && isNum(r[ioKey]) && isNum(r[ioIn]); }),
        function (r) { return r._variant; }).forEach(function (rs, v) {
        ioSeries.push({name: v, color: d.colors[v], pts: rs.map(function (r) {
          return [r[ioIn], r[ioKey], tipOf(r, 'input ' + fmt(r[ioIn]) + ' → ' + fmt(r[ioKey]) + ' (' + ioKey + ')')]; })});
      });
      var unit = ioKey.indexOf('deg') > 0 ? ' (degrees)' : ' (/ bbox diagonal)';
      addPanel(ioPanels, chart({w: 440, h: 340, xlabel: ioIn + unit, ylabel: ioKey + unit, xlog: true, ylog: true, diag: true, series: ioSeries}));
      histPlot(plots, {rows: ok, colors: d.colors}, hidden, 'Triangle quality of the results: min-angle histogram per method', mkLeg([]));
    }
    render();
    RERENDER.push(render);
  }

  function aggregate(rs, key) { // one point per variant: [median time, mean metric, tip, n, variant]
    var out = [];
    groupBy(rs, function (r) { return r._variant; }).forEach(function (g, v) {
      var t = median(g.map(function (r) { return r.time_s; }).filter(isNum)), y = mean(g.map(function (r) { return r[key]; }));
      out.push([t, y, tipOf(g[0], key + ' ' + fmt(y) + (g.length > 1 ? ' (mean of ' + g.length + ' seeds)' : '') + ', time ' +
        fmtTime(t) + (g.length > 1 ? ' (median)' : ''), g), g.length, v]);
    });
    return out;
  }

  function simplificationSection(d) {
    var host = document.getElementById('plots-simplification');
    var state = {metric: 'hausdorff', mesh: ''};
    var hidden = new Set();
    var controls = el('div', {'class': 'controls'});
    var leg = el('div'), plots = el('div');
    host.appendChild(controls); host.appendChild(leg); host.appendChild(plots);
    controls.appendChild(el('label', {}, ['accuracy metric ', selectEl([['hausdorff', 'hausdorff — symmetric Hausdorff to the input'],
      ['surface_dist_mean', 'surface_dist_mean — mean surface distance to the input']], state.metric, function (v) { state.metric = v; render(); })]));
    var mf = meshFilter(d.rows, state, function () { render(); });
    if (mf) controls.appendChild(mf);
    function render() {
      leg.innerHTML = ''; plots.innerHTML = '';
      var mkLeg = function () { return legend(d.variants, d.colors, hidden, render); };
      var key = state.metric;
      var all = d.rows.filter(function (r) { return !state.mesh || r.mesh === state.mesh; });
      var ok = all.filter(function (r) { return r.status === 'ok' && !hidden.has(r._variant); });
      var vis = ok.filter(function (r) { return isNum(r[key]) && isNum(r.out_faces); });
      var bt = el('table', {'class': 'best'});
      bt.innerHTML = '<tr><th>mesh</th><th>noise</th><th>target</th><th>most accurate</th><th>' + esc(key) +
        '</th><th>faces</th><th>time</th><th>fastest</th><th>its ' + esc(key) + '</th><th>its time</th></tr>';
      var nInvalid = vis.filter(function (r) { return r._invalid; }).length;
      var tol = tolOf(d.T.spec, key), visSet = new Set(vis);
      groupBy(inCellOrder(all), function (r) { return r.mesh + '|' + r._noise + '|' + r._target; }).forEach(function (cell) {
        var rows = winnerRows(cell, key, visSet, bt, 7, cell[0]._target);
        if (!rows.length) return;
        // one entry per method: mean metric and faces over seeds, median time
        var rs = [];
        groupBy(rows, function (r) { return r._variant; }).forEach(function (g, v) {
          var o = Object.assign({}, g[0]);
          o[key] = mean(g.map(function (r) { return r[key]; }));
          o.out_faces = Math.round(mean(g.map(function (r) { return r.out_faces; })));
          var ts = g.map(function (r) { return r.time_s; }).filter(isNum);
          o.time_s = ts.length ? median(ts) : null;
          rs.push(o);
        });
        var best = pickBest(rs, function (r) { return r[key]; }, function (r) { return r._variant; }, true);
        var tied = tiedWith(rs, best, function (r) { return r[key]; }, function (r) { return r._variant; }, rows, key, tol, true);
        var timed = rs.filter(function (r) { return isNum(r.time_s); });
        var fast = timed.length ? pickBest(timed, function (r) { return r.time_s; }, function (r) { return r._variant; }, true) : null;
        var fastTied = fast ? timed.filter(function (r) { return r !== fast && timeTiedWith(rows, fast._variant, r._variant); })
          .map(function (r) { return r._variant; }) : [];
        var fastCells = fast ? '<td>' + esc(fast._variant) + timeTiedNote(fastTied) + '</td><td class="num">' +
          valueText(rows, fast._variant, key, tol, 4) + '</td><td class="num">' + timeCell(fast.time_s, rows, fast._variant) + '</td>' :
          '<td class="muted">— (nothing timed)</td><td></td><td></td>';
        bt.appendChild(el('tr', {html: '<td>' + esc(best.mesh) + '</td><td>' + esc(best._noise) + '</td><td>' + esc(fmt(best._target)) +
          '</td><td><i style="color:' + d.colors[best._variant] + '">●</i> ' + esc(best._variant) + tiedNote(tied) + '</td><td class="num">' + valueText(rows, best._variant, key, tol, 4) +
          '</td><td class="num">' + best.out_faces + '</td><td class="num">' + timeCell(best.time_s, rows, best._variant) + '</td>' +
          fastCells}));
      });
      plots.appendChild(el('h4', {text: 'Most accurate and fastest method per mesh, noise level and target (mean over seeds)'}));
      plots.appendChild(bt);
      plots.appendChild(valueNote(key, tol));
      plots.appendChild(invalidNote(nInvalid));
      var panels = panelGroup(plots, key + ' vs output face count, per mesh and noise level',
        'One line per method through its face targets (log–log; mean over seeds). Lower-left is better: fewer faces, ' +
        'closer to the input. Distances are fractions of the bounding-box diagonal.' + (showInvalid ? '' : ' Invalid results are not plotted.'), mkLeg);
      groupBy(vis.filter(validOrShown), function (r) { return r.mesh + ' · ' + r._noise; }).forEach(function (rs, title) {
        var series = [];
        groupBy(rs, function (r) { return r._variant; }).forEach(function (vr, v) {
          var pts = [];
          groupBy(vr, function (r) { return r._target; }).forEach(function (g) {
            var x = mean(g.map(function (r) { return r.out_faces; })), y = mean(g.map(function (r) { return r[key]; }));
            pts.push([x, y, tipOf(g[0], 'target ' + fmt(g[0]._target) + ': ' + Math.round(x) + ' faces of ' + g[0].n_faces +
              ', ' + key + ' ' + fmt(y) + ', time ' + fmtTime(median(g.map(function (r) { return r.time_s; }))) +
              (g.length > 1 ? ' (means of ' + g.length + ' seeds, median time)' : ''), g)]);
          });
          pts.sort(function (a, b) { return a[0] - b[0]; });
          series.push({name: v, color: d.colors[v], pts: pts, line: true});
        });
        addPanel(panels, chart({title: title, xlabel: 'output faces', ylabel: key + ' (/ bbox diagonal)', xlog: true, ylog: true, series: series}));
      });
      var tp = panelGroup(plots, 'Time vs output face count', 'Median time of the method call; one point per case.', mkLeg);
      var ts = [];
      groupBy(vis.filter(function (r) { return isNum(r.time_s); }), function (r) { return r._variant; }).forEach(function (rs, v) {
        ts.push({name: v, color: d.colors[v], pts: rs.map(function (r) {
          return [r.out_faces, r.time_s, tipOf(r, r.out_faces + ' faces, ' + fmtTime(r.time_s))]; })});
      });
      addPanel(tp, chart({w: 560, h: 280, xlabel: 'output faces', ylabel: 'time (s)', xlog: true, ylog: true, series: ts}));
      histPlot(plots, {rows: ok, colors: d.colors}, hidden, 'Triangle quality of the results: min-angle histogram per method', mkLeg);
    }
    render();
    RERENDER.push(render);
  }

  // ------------------------------------------------------------------ 3D views (canvas 2D painter's algorithm)
  var VIRIDIS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  var DIVERGING = [[33, 102, 172], [146, 197, 222], [247, 247, 247], [244, 165, 130], [178, 24, 43]];
  function ramp(stops, t) {                // t in [0, 1] -> the colour between evenly spaced stops
    t = Math.max(0, Math.min(1, t)) * (stops.length - 1);
    var i = Math.min(Math.floor(t), stops.length - 2), f = t - i, a = stops[i], b = stops[i + 1];
    return [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, a[2] + (b[2] - a[2]) * f];
  }
  function cmap(t) { return ramp(VIRIDIS, t); }
  function dmap(t) { return ramp(DIVERGING, t); }   // signed quantities: blue below 0, white at 0, red above
  function decode(b64, Type) {
    var s = atob(b64), u = new Uint8Array(s.length);
    for (var i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
    return new Type(u.buffer);
  }
  function unpack(m, lo, span) {
    var q = decode(m.V, Uint16Array), V = new Float32Array(q.length);
    for (var i = 0; i < q.length; i++) V[i] = lo[i % 3] + q[i] / 65535 * span;
    return {V: V, F: decode(m.F, Uint32Array), e: m.e ? decode(m.e, Uint8Array) : null, nv: m.nv, nf: m.nf,
      iso: m.e && m.isolines > 0 ? m.isolines : 0, signed: !!m.signed};
  }
  function drawMesh(canvas, mesh, cam, center, radius) {
    var ctx = canvas.getContext('2d'), w = canvas.width, h = canvas.height;
    ctx.fillStyle = '#ffffff'; ctx.fillRect(0, 0, w, h);
    var cy = Math.cos(cam.yaw), sy = Math.sin(cam.yaw), cp = Math.cos(cam.pitch), sp = Math.sin(cam.pitch);
    // R = Rx(pitch) * Ry(yaw)
    var r00 = cy, r01 = 0, r02 = sy, r10 = sp * sy, r11 = cp, r12 = -sp * cy, r20 = -cp * sy, r21 = sp, r22 = cp * cy;
    var s = cam.zoom * 0.47 * Math.min(w, h) / radius, n = mesh.nv, V = mesh.V, F = mesh.F, e = mesh.e;
    var X = new Float32Array(n), Y = new Float32Array(n), Z = new Float32Array(n);
    for (var i = 0; i < n; i++) {
      var x = V[3 * i] - center[0], y = V[3 * i + 1] - center[1], z = V[3 * i + 2] - center[2];
      X[i] = r00 * x + r01 * y + r02 * z; Y[i] = r10 * x + r11 * y + r12 * z; Z[i] = r20 * x + r21 * y + r22 * z;
    }
    var m = mesh.nf, depth = new Float32Array(m), order = new Uint32Array(m);
    for (var f = 0; f < m; f++) { depth[f] = Z[F[3 * f]] + Z[F[3 * f + 1]] + Z[F[3 * f + 2]]; order[f] = f; }
    order.sort(function (a, b) { return depth[a] - depth[b]; });
    var L = [-0.35, 0.45, 0.82], ln = Math.hypot(L[0], L[1], L[2]);
    L = [L[0] / ln, L[1] / ln, L[2] / ln];
    ctx.lineWidth = 0.6; ctx.lineJoin = 'round';
    var hw = w / 2, hh = h / 2;
    for (var k = 0; k < m; k++) {
      var t = order[k], a = F[3 * t], b = F[3 * t + 1], c = F[3 * t + 2];
      var ux = X[b] - X[a], uy = Y[b] - Y[a], uz = Z[b] - Z[a], vx = X[c] - X[a], vy = Y[c] - Y[a], vz = Z[c] - Z[a];
      var nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx, nl = Math.hypot(nx, ny, nz);
      if (!(nl > 0)) continue;
      var sh = 0.28 + 0.72 * Math.abs(nx * L[0] + ny * L[1] + nz * L[2]) / nl;
      var col = e ? (mesh.signed ? dmap : cmap)((e[a] + e[b] + e[c]) / 765) : [206, 209, 216];
      var rgb = 'rgb(' + (col[0] * sh | 0) + ',' + (col[1] * sh | 0) + ',' + (col[2] * sh | 0) + ')';
      ctx.fillStyle = rgb; ctx.strokeStyle = rgb;
      ctx.beginPath();
      ctx.moveTo(hw + s * X[a], hh - s * Y[a]); ctx.lineTo(hw + s * X[b], hh - s * Y[b]); ctx.lineTo(hw + s * X[c], hh - s * Y[c]);
      ctx.closePath(); ctx.fill(); ctx.stroke();
      if (mesh.iso) isoSegments(ctx, mesh.iso, [a, b, c], e, function (i) { return [hw + s * X[i], hh - s * Y[i]]; });
    }
  }
  // level lines of the per-vertex values across one face (drawn in the face's depth order)
  function isoSegments(ctx, n, tri, e, proj) {
    var step = 255 / n, lo = Math.min(e[tri[0]], e[tri[1]], e[tri[2]]), hi = Math.max(e[tri[0]], e[tri[1]], e[tri[2]]);
    ctx.save(); ctx.strokeStyle = 'rgba(20,20,30,0.85)'; ctx.lineWidth = 1.1;
    for (var k = Math.ceil(lo / step - 0.5); (k + 0.5) * step < hi; k++) {
      var lv = (k + 0.5) * step, pts = [];
      if (lv <= lo) continue;
      for (var j = 0; j < 3; j++) {
        var p = tri[j], q = tri[(j + 1) % 3], ep = e[p], eq = e[q];
        if ((ep < lv) !== (eq < lv)) {
          var t = (lv - ep) / (eq - ep), P = proj(p), Q = proj(q);
          pts.push([P[0] + t * (Q[0] - P[0]), P[1] + t * (Q[1] - P[1])]);
        }
      }
      if (pts.length === 2) { ctx.beginPath(); ctx.moveTo(pts[0][0], pts[0][1]); ctx.lineTo(pts[1][0], pts[1][1]); ctx.stroke(); }
    }
    ctx.restore();
  }
  function viewCard(v) {
    var card = el('div', {'class': 'view', 'data-case': v.case_id});
    card.appendChild(el('h4', {text: (v.title || 'case ' + v.case_id)}));
    var sub = (v.why ? v.why + ' — ' : '') + 'case ' + v.case_id + (v.params ? ', params ' + paramText(v.params) : '') +
      (v.metric && isNum(v.value) ? ', ' + v.metric + (isNum(v.upper) && fmt(v.upper) !== fmt(v.value) ?
        ' in [' + fmt(v.value) + ', ' + fmt(v.upper) + '] (certified bracket)' : ' = ' + fmt(v.value)) : '');
    card.appendChild(el('div', {'class': 'caption', text: sub}));
    if (v.error) { card.appendChild(el('p', {'class': 'err', text: 'No 3D view: ' + v.error})); return {card: card, ok: false}; }
    if (v.source) card.appendChild(el('div', {'class': 'caption', text: v.source}));
    if (v.mismatch) card.appendChild(el('p', {'class': 'warn', text: v.mismatch}));
    var meshes = v.meshes.map(function (m) { return unpack(m, v.lo, v.span); });
    var ref = meshes[0], lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (var i = 0; i < ref.V.length; i++) { lo[i % 3] = Math.min(lo[i % 3], ref.V[i]); hi[i % 3] = Math.max(hi[i % 3], ref.V[i]); }
    var center = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2];
    var radius = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2 || 1;
    var home = {yaw: 0.45, pitch: 0.3, zoom: 1};
    var cam = {yaw: home.yaw, pitch: home.pitch, zoom: 1};
    var dpr = Math.min(window.devicePixelRatio || 1, 2), size = 320;
    var row = el('div', {'class': 'canvases'}), canvases = [];
    v.meshes.forEach(function (m, j) {
      var cv = el('canvas', {width: Math.round(size * dpr), height: Math.round(size * dpr),
        style: 'width:' + size + 'px;height:' + size + 'px'});
      var capHtml = '<b>' + esc(m.label) + '</b> — ' + esc(isNum(m.nf) ? m.nf.toLocaleString('en') : String(m.nf)) + ' faces' + (m.note ? ' (' + esc(m.note) + ')' : '') +
        '<br>' + esc(m.what) + (isNum(m.emean) ? '<br>mean ' + fmt(m.emean, 3) + (m.signed && isNum(m.eminv) ?
          ', min ' + fmt(m.eminv, 3) : '') + ', max ' + fmt(m.emaxv, 3) : '');
      var cap = el('figcaption', {html: capHtml});
      if (isNum(m.escale)) {
        cap.appendChild(el('div', {'class': 'colorbar'}, [el('span', {text: m.signed ? '−' + fmt(m.escale, 3) : '0'}),
          el('span', {'class': m.signed ? 'bar signed' : 'bar'}), el('span', {text: fmt(m.escale, 3) + '+'})]));
      }
      var fig = el('figure', {}, [cv, cap]);
      row.appendChild(fig); canvases.push(cv);
    });
    card.appendChild(row);
    if (v.scale_note) card.appendChild(el('div', {'class': 'caption', text: 'Colours: ' + v.scale_note +
      '; larger values saturate. Lengths are ' + v.unit + '.'}));
    var pending = false;
    function redraw() {
      pending = false;
      canvases.forEach(function (cv, j) { drawMesh(cv, meshes[j], cam, center, radius); });
    }
    function schedule() { if (!pending) { pending = true; requestAnimationFrame(redraw); } }
    var drag = null;
    canvases.forEach(function (cv) {
      cv.addEventListener('pointerdown', function (e) { drag = [e.clientX, e.clientY]; cv.setPointerCapture(e.pointerId); cv.style.cursor = 'grabbing'; });
      cv.addEventListener('pointermove', function (e) {
        if (!drag) return;
        cam.yaw += (e.clientX - drag[0]) * 0.01;
        cam.pitch = Math.max(-1.57, Math.min(1.57, cam.pitch + (e.clientY - drag[1]) * 0.01));
        drag = [e.clientX, e.clientY]; schedule();
      });
      cv.addEventListener('pointerup', function () { drag = null; cv.style.cursor = 'grab'; });
      cv.addEventListener('wheel', function (e) {
        e.preventDefault(); cam.zoom = Math.max(0.3, Math.min(8, cam.zoom * Math.exp(-e.deltaY * 0.0015))); schedule();
      }, {passive: false});
      cv.addEventListener('dblclick', function () { cam.yaw = home.yaw; cam.pitch = home.pitch; cam.zoom = 1; schedule(); });
    });
    redraw();
    return {card: card, ok: true};
  }
  function viewsSection() {
    var host = document.getElementById('view-list');
    var views = D.views || [];
    if (!views.length) {
      host.appendChild(el('p', {'class': 'muted', text: D.views_note || 'No 3D views: this run has no case with a mesh to show and status ok.'}));
      body.dataset.view3d = 'none';
      return;
    }
    var nOk = 0;
    views.forEach(function (v) {
      guard('3D view ' + v.case_id, host, function () { var r = viewCard(v); host.appendChild(r.card); if (r.ok) nOk++; });
    });
    body.dataset.view3d = nOk ? 'ready' : 'failed';
    body.dataset.view3dCount = String(nOk);
  }



  // ------------------------------------------------------------------ validity and leaderboard
  var RERENDER = [];
  var showInvalid = false;
  function validOrShown(r) { return showInvalid || !r._invalid; }
  function invalidNote(n) {
    if (!n) return el('span');
    return el('p', {'class': 'caption', text: n + ' row(s) are not valid results (' +
      'diverged, worse than the noisy input, over the face target, non-manifold from a manifold input or topology-changing output) and are ' +
      (showInvalid ? 'included in' : 'left out of') + ' the winners above and the accuracy plots below; the checkbox at the top of ' +
      'the page toggles them.'});
  }
  function cdDiagram(g) {
    // Demšar's critical-difference diagram: mean ranks on an axis, variants whose ranks differ by less than CD joined
    var ms = g.methods.slice().sort(function (a, b) { return a.mean_rank - b.mean_rank; });
    var label = function (m) { return m.method + ' (' + fmt(m.mean_rank, 3) + ')' + (m.invalid ? ' ⚠' + m.invalid : ''); };
    var half0 = Math.ceil(ms.length / 2), CH = 6.4;   // label margins from the longest label on each side (11 px font)
    var wide = function (xs) { return xs.reduce(function (a, m) { return Math.max(a, label(m).length); }, 0); };
    var left = Math.max(120, 20 + CH * wide(ms.slice(0, half0))), rm = Math.max(120, 20 + CH * wide(ms.slice(half0)));
    var k = Math.max(g.k, 2), W = Math.round(left + 420 + rm), right = left + 420, top = 46, rowH = 18;
    var H = top + 24 + Math.ceil(ms.length / 2) * rowH + 30;
    var x = function (r) { return left + (r - 1) / (k - 1) * (right - left); };
    var svg = sv('svg', {width: W, height: H, 'class': 'chart cd', viewBox: '0 0 ' + W + ' ' + H});
    svg.appendChild(sv('line', {x1: left, x2: right, y1: top, y2: top, stroke: '#333'}));
    for (var t = 1; t <= k; t++) {
      svg.appendChild(sv('line', {x1: x(t), x2: x(t), y1: top - 5, y2: top, stroke: '#333'}));
      var tx = sv('text', {x: x(t), y: top - 8, 'text-anchor': 'middle', 'font-size': 11}); tx.textContent = t; svg.appendChild(tx);
    }
    // Demšar: the post-hoc test only where the Friedman test rejects; otherwise no pair is shown to differ
    var applies = isNum(g.cd) && isNum(g.p) && g.p < 0.05;
    if (applies) {
      svg.appendChild(sv('line', {x1: left, x2: left + g.cd / (k - 1) * (right - left), y1: 14, y2: 14, stroke: '#c00', 'stroke-width': 2}));
      var ct = sv('text', {x: left, y: 10, 'font-size': 11}); ct.textContent = 'CD = ' + fmt(g.cd, 3) + ' (Nemenyi, α = 0.05)'; svg.appendChild(ct);
    } else if (isNum(g.cd)) {
      var nt = sv('text', {x: left, y: 10, 'font-size': 11, 'class': 'cd-not-applied'});
      nt.textContent = isNum(g.p) ? 'no critical difference: the Friedman test does not reject (p ≥ 0.05), so no pair is shown to differ'
        : 'no critical difference: no Friedman test here (one cell or one method)';
      svg.appendChild(nt);
    }
    var half = Math.ceil(ms.length / 2);
    ms.forEach(function (m, i) {
      var onLeft = i < half, j = onLeft ? i : ms.length - 1 - i;
      var y = top + 24 + j * rowH, xm = x(m.mean_rank), xe = onLeft ? left - 10 : right + 10;
      svg.appendChild(sv('polyline', {points: xm + ',' + top + ' ' + xm + ',' + y + ' ' + xe + ',' + y, fill: 'none', stroke: '#555'}));
      var lt = sv('text', {x: onLeft ? xe - 4 : xe + 4, y: y + 4, 'text-anchor': onLeft ? 'end' : 'start', 'font-size': 11});
      lt.textContent = label(m);
      svg.appendChild(lt);
    });
    if (applies) {                          // maximal groups not significantly different: thick bars
      var yb = top + 8, start = 0;
      for (var a = 0; a < ms.length; a++) {
        var b = a;
        while (b + 1 < ms.length && ms[b + 1].mean_rank - ms[a].mean_rank < g.cd) b++;
        if (b > a && b >= start) {
          svg.appendChild(sv('line', {x1: x(ms[a].mean_rank) - 3, x2: x(ms[b].mean_rank) + 3, y1: yb, y2: yb,
            stroke: '#000', 'stroke-width': 3, 'class': 'clique'}));
          yb += 5; start = b + 1;
        }
      }
    }
    plotsRendered++;
    return svg;
  }
  function leaderboardSection() {
    var host = document.getElementById('leaderboard-body');
    var box = el('label', {}, [el('input', {type: 'checkbox', id: 'show-invalid'}), ' include invalid results in the winner tables']);
    host.appendChild(box);
    box.querySelector('input').addEventListener('change', function (e) {
      showInvalid = e.target.checked;
      RERENDER.forEach(function (f) { f(); });
    });
    var groups = D.leaderboard || [];
    if (!groups.length) { host.appendChild(el('p', {'class': 'muted', text: D.no_ranking || 'No ranking.'})); return; }
    groups.forEach(function (g) {
      var card = el('div', {'class': 'lb'});
      card.appendChild(el('h4', {text: g.task + ': ' + g.metric + ' (' + g.better + ' is better), ' + g.cells + (g.cells === 1 ? ' cell' : ' cells') + ', Friedman ' +
        (g.p_text || 'p = —')}));
      if (g.methods.length >= 2) {
        var cd = cdDiagram(g);
        cd.setAttribute('data-name', ('cd ' + g.task + ' ' + g.metric).replace(/[^A-Za-z0-9._-]+/g, '_'));
        card.appendChild(el('div', {'class': 'cdbox'}, [cd, svgDownload(cd)]));   // every plot downloads as SVG
      }
      var t = el('table', {'class': 'best'});
      t.innerHTML = '<tr><th>method</th><th>mean rank</th><th>missing cells</th><th>invalid cells</th></tr>' +
        g.methods.map(function (m) { return '<tr><td>' + esc(m.method) + '</td><td class="num">' + m.mean_rank.toFixed(2) +
          '</td><td class="num">' + m.missing + '</td><td class="num">' + m.invalid + '</td></tr>'; }).join('');
      card.appendChild(t);
      if (g.left_out) card.appendChild(el('p', {'class': 'muted', text: 'Left out: ' + g.left_out + ': ' + g.left_out_why + '.'}));
      host.appendChild(card);
    });
  }

  // A task without a dedicated renderer: built from its declared metric specs (run.json).
  function genericSection(task, d) {
    var host = document.getElementById('plots-' + task);
    var spec = d.T.spec || {};
    var metrics = (spec.metrics || []).filter(function (m) {
      return (m.better === 'lower' || m.better === 'higher') && d.rows.some(function (r) { return isNum(r[m.name]); });
    });
    if (!metrics.length) { host.appendChild(el('p', {'class': 'muted', text: 'No numeric metric to plot.'})); return; }
    var ranked = metrics.filter(function (m) { return m.rank; });
    var state = {metric: (spec.view_metric && metrics.some(function (m) { return m.name === spec.view_metric; })) ?
      spec.view_metric : (ranked[0] || metrics[0]).name, mesh: ''};
    var hidden = new Set();
    var controls = el('div', {'class': 'controls'}), leg = el('div'), plots = el('div');
    host.appendChild(controls); host.appendChild(leg); host.appendChild(plots);
    controls.appendChild(el('label', {}, ['metric ', selectEl(metrics.map(function (m) {
      return [m.name, m.name + ' — ' + m.doc + (m.unit ? ' [' + m.unit + ']' : '') + ' (' + m.better + ' is better)'];
    }), state.metric, function (v) { state.metric = v; render(); })]));
    var mf = meshFilter(d.rows, state, function () { render(); });
    if (mf) controls.appendChild(mf);
    function render() {
      leg.innerHTML = ''; plots.innerHTML = '';
      var key = state.metric;
      var m = metrics.filter(function (x) { return x.name === key; })[0];
      var lower = m.better === 'lower';
      var vis = d.rows.filter(function (r) {
        return r.status === 'ok' && isNum(r[key]) && (!state.mesh || r.mesh === state.mesh) && !hidden.has(r._variant) &&
          validOrShown(r);
      });
      var bt = el('table', {'class': 'best'});
      var axes = vis.some(function (r) { return r._axis; });    // the task's axis parameters (e.g. k): ranked apart
      bt.innerHTML = '<tr><th>mesh</th><th>noise</th>' + (axes ? '<th>setting</th>' : '') + '<th>best</th><th>' + esc(key) +
        (m.unit ? ' [' + esc(m.unit) + ']' : '') + '</th><th>time</th></tr>';
      var visSet = new Set(vis);
      groupBy(inCellOrder(d.rows.filter(function (r) { return !state.mesh || r.mesh === state.mesh; })), function (r) {
        return r.mesh + '|' + r._noise + '|' + (r._axis || '');
      }).forEach(function (cell) {
        var rows = winnerRows(cell, key, visSet, bt, 3, axes ? (cell[0]._axis || '') : undefined);
        if (!rows.length) return;
        var rs = [];
        groupBy(rows, function (r) { return r._variant; }).forEach(function (g) {
          var o = Object.assign({}, g[0]);
          o[key] = mean(g.map(function (r) { return r[key]; }));
          var ts = g.map(function (r) { return r.time_s; }).filter(isNum);
          o.time_s = ts.length ? median(ts) : null;
          rs.push(o);
        });
        var best = pickBest(rs, function (r) { return r[key]; }, function (r) { return r._variant; }, lower);
        var tol = tolOf(spec, key);
        var tied = tiedWith(rs, best, function (r) { return r[key]; }, function (r) { return r._variant; }, rows, key, tol, lower);
        bt.appendChild(el('tr', {html: '<td>' + esc(best.mesh) + '</td><td>' + esc(best._noise) + '</td>' +
          (axes ? '<td>' + esc(best._axis || '') + '</td>' : '') + '<td><i style="color:' +
          d.colors[best._variant] + '">●</i> ' + esc(best._variant) + tiedNote(tied) + '</td><td class="num">' +
          valueText(rows, best._variant, key, tol, 4) + '</td><td class="num">' + timeCell(best.time_s, rows, best._variant) + '</td>'}));
      });
      plots.appendChild(el('h4', {text: 'Best method per mesh, noise level' + (axes ? ' and setting' : '') + ' by ' + key +
        ' (mean over seeds)'}));
      plots.appendChild(bt);
      plots.appendChild(valueNote(key, tolOf(spec, key)));
      var bad = d.rows.filter(function (r) {
        return (!state.mesh || r.mesh === state.mesh) && r.status === 'ok' && isNum(r[key]) && r._invalid; });
      [[bad.filter(function (r) { return !r._missing; }), ' row(s) are not valid results (', ') and are ' +
        (showInvalid ? 'included in' : 'left out of') + ' the table above and the plots below; the checkbox at the top of the page toggles them.'],
       [bad.filter(function (r) { return r._missing; }), ' row(s) are no measurement (', ') and are left out of the table above.']
      ].forEach(function (x) {
        if (x[0].length) plots.appendChild(el('p', {'class': 'caption', text: x[0].length + x[1] +
          uniq(x[0].map(function (r) { return r._invalid; })).join('; ') + x[2]}));
      });
      // a lower-is-better metric: one point per method (mean over seeds, median time) and the Pareto front
      var tol = tolOf(spec, key);
      var panels = panelGroup(plots, key + ' vs time, per mesh' + (axes ? ' and setting' : ''), (lower ?
        'One point per method: x its median time (log), y its mean ' + esc(key) + ' over seeds. Black-ringed points and the ' +
        'dashed staircase are the Pareto front: no other method in the panel is faster beyond the timing noise and not ' +
        'less accurate, or not slower and more accurate beyond the metric\'s tolerance (as the winner tables tie them)'
        : 'One point per case') + '; ' + esc(m.better) + ' is better' + (m.unit ? ' (' + esc(m.unit) + ')' : '') + '.',
        function () { return legend(d.variants, d.colors, hidden, render, lower ? ['Pareto front'] : undefined); });
      // never a row that is no measurement (the reference scored against itself), checkbox or not
      groupBy(vis.filter(function (r) { return isNum(r.time_s) && validOrShown(r) && !r._missing; }), function (r) {
        return r.mesh + ' · ' + r._noise + (r._axis ? ' · ' + r._axis : '');        // one panel per setting (e.g. k)
      }).forEach(function (rs, title) {
        var series = [], front = [];
        if (lower) {
          var pts = aggregate(rs, key);
          front = pareto(pts, tol, rs, key);
          var onFront = new Set(front);
          groupBy(pts, function (p) { return p[4]; }).forEach(function (ps, v) {
            series.push({name: v, color: d.colors[v], pts: ps.map(function (p) { return [p[0], p[1], p[2], onFront.has(p)]; })});
          });
        } else {
          groupBy(rs, function (r) { return r._variant; }).forEach(function (vr, v) {
            series.push({name: v, color: d.colors[v], pts: vr.map(function (r) {
              return [r.time_s, r[key], tipOf(r, key + ' ' + fmt(r[key]) + ', time ' + fmtTime(r.time_s))]; })});
          });
        }
        addPanel(panels, chart({title: title, xlabel: 'time (s)', ylabel: key, xlog: true, ylog: false, series: series,
                                front: front}));
      });
      if (!state.mesh) convergencePanels(plots, d, key, hidden);    // over a family's meshes: not one mesh's
      noisePanels(plots, d, vis, key);
      sweepPanels(plots, vis, key);
    }
    render();
    RERENDER.push(render);
  }

  // the metric against the noise level, per mesh and noise model (clean rows at level 0), one line per
  // variant and setting; drawn only where a line has two levels or more
  function noisePanels(plots, d, vis, key) {
    var clean = vis.filter(function (r) { return r.noise_model === 'none'; });
    var noisy = vis.filter(function (r) { return r.noise_model !== 'none' && isNum(r.noise_level); });
    var panels = [], drawn = new Map();          // series name -> colour: the legend lists what got a line
    var axisColors = paletteFor(noisy.filter(function (r) { return r._axis; }).map(function (r) { return r._variant + ' ' + r._axis; }));
    groupBy(noisy, function (r) { return r.mesh + ' · ' + r.noise_model; }).forEach(function (g, title) {
      var rows = g.concat(clean.filter(function (c) { return c.mesh === g[0].mesh; }));
      var series = [];
      groupBy(rows, function (r) { return r._variant + (r._axis ? ' ' + r._axis : ''); }).forEach(function (vr, name) {
        var byX = groupBy(vr, function (r) { return r.noise_model === 'none' ? 0 : r.noise_level; });
        var xs = Array.from(byX.keys()).sort(function (a, b) { return a - b; });
        if (xs.length < 2) return;
        var color = vr[0]._axis ? axisColors[name] : d.colors[vr[0]._variant];   // k = 6 and k = 10 apart
        drawn.set(name, color);
        series.push({name: name, color: color, line: true, r: 3, pts: xs.map(function (x) {
          var y = mean(byX.get(x).map(function (r) { return r[key]; }));
          return [x, y, name + '\n' + title + '\nlevel ' + fmt(x) + ', ' + key + ' ' + fmt(y)];
        })});
      });
      if (series.length) panels.push(chart({title: title, xlabel: 'noise level', ylabel: key, ylog: false, series: series}));
    });
    if (!panels.length) return;
    var group = panelGroup(plots, key + ' vs noise level, per mesh and noise model',
      'Mean over seeds; noise level = σ / mean edge length (0: the clean mesh).', function () {
        return staticLegend(Array.from(drawn.keys()).sort(), function (name) { return drawn.get(name); });
      });
    panels.forEach(function (p) { addPanel(group, p); });
  }
  // the metric against every numeric parameter that some method sweeps over >= 3 values (e.g. the
  // heat method's time factor): one line per method and its other parameters, mean over seeds
  // convergence under refinement (a task declaring mean_edge_length: curvature): the metric against
  // the mean edge length h on log-log axes per mesh family, one line per variant, and the observed
  // order, the fitted slope of log error against log h (computed in Python: harness.report.convergence)
  function convergencePanels(plots, d, key, hidden) {
    var recs = (d.T.convergence || []).filter(function (c) { return c.metric === key && !hidden.has(c.variant); });
    if (!recs.length) return;
    var famOf = function (c) { return c.family + ' · ' + c.noise; };    // a panel and a column each
    var fams = uniq(recs.map(famOf)).sort();
    var vars = uniq(recs.map(function (c) { return c.variant; })).sort();
    var t = el('table', {'class': 'best convergence'});
    var order = function (v, f) {
      var c = recs.filter(function (c) { return c.variant === v && famOf(c) === f; })[0];
      if (!c) return '';
      if (isNum(c.order)) return c.order.toFixed(2);
      if (c.at_floor && c.at_floor === c.points.length) return 'exact (every error ≤ ' + fmt(c.floor) + ')';
      return '— (' + (c.points.length - (c.at_floor || 0)) + ' resolutions' + (c.floor ? ' above ' + fmt(c.floor) : '') + ')';
    };
    t.innerHTML = '<tr><th>method</th>' + fams.map(function (f) { return '<th>' + esc(f) + '</th>'; }).join('') + '</tr>' +
      vars.map(function (v) {
        return '<tr><td>' + esc(v) + '</td>' + fams.map(function (f) { return '<td class="num">' + order(v, f) + '</td>'; }).join('') + '</tr>';
      }).join('');
    plots.appendChild(el('h4', {text: 'Observed order of ' + key + ' under refinement (slope of log ' + key + ' against log h)'}));
    plots.appendChild(t);
    plots.appendChild(el('p', {'class': 'caption', text: 'h: the mean edge length of the clean input; error ~ C h^p, p the ' +
      'least-squares slope over three resolutions or more of one surface (a mesh family: the same procedural surface at ' +
      'several subdivisions, resolutions or point counts), means over seeds of valid results; errors at or below the ' +
      'metric\'s compare tolerance are rounding, left out of the fit. A positive p converges; ' +
      'p near 0 does not (the cotan mean curvature on irregular triangulations, in the literature).'}));
    var panels = panelGroup(plots, key + ' vs mean edge length, per mesh family (log-log)',
      'One line per method; its observed order p is in the table above (and in each point\'s tooltip).', function () {
        return staticLegend(vars, function (name) { return d.colors[name]; });
      });
    groupBy(recs, famOf).forEach(function (cs, title) {
      var series = cs.map(function (c) {
        return {name: c.variant, color: d.colors[c.variant], line: true, r: 3, pts: c.points.map(function (p) {
          return [p[0], p[1], c.variant + '\n' + title + '\nh ' + fmt(p[0]) + ', ' + key + ' ' + fmt(p[1]) +
            (isNum(c.order) ? '\norder ' + c.order.toFixed(2) : '')];
        })};
      });
      addPanel(panels, chart({title: title, xlabel: 'mean edge length h', ylabel: key, xlog: true, ylog: true, series: series}));
    });
  }
  function sweepPanels(plots, vis, key) {
    var P = vis.map(function (r) { try { return JSON.parse(r.params) || {}; } catch (e) { return {}; } });
    var names = uniq([].concat.apply([], P.map(function (p) { return Object.keys(p); }))).sort();
    names.forEach(function (pn) {
      var pts = [];
      vis.forEach(function (r, i) {
        var x = P[i][pn];
        if (!isNum(x)) return;
        var rest = Object.assign({}, P[i]); delete rest[pn];
        var other = paramText(JSON.stringify(rest));
        pts.push({r: r, x: x, series: r.method + (other ? ' ' + other : '')});
      });
      var lines = groupBy(pts, function (p) { return p.r.mesh + '|' + p.r._noise + '|' + p.series; });
      if (!Array.from(lines.values()).some(function (g) { return uniq(g.map(function (p) { return p.x; })).length >= 3; })) return;
      var positive = pts.every(function (p) { return p.x > 0; });
      var colors = paletteFor(pts.map(function (p) { return p.series; }));
      var drawn = [];                         // the legend lists the series that get a line (two x or more)
      lines.forEach(function (g) { if (uniq(g.map(function (p) { return p.x; })).length >= 2) drawn.push(g[0].series); });
      var panels = panelGroup(plots, key + ' vs ' + pn + ', per mesh',
        'One line per method and its other parameters; mean over seeds.', function () {
          return staticLegend(uniq(drawn).sort(), function (name) { return colors[name]; });
        });
      groupBy(pts, function (p) { return p.r.mesh + ' · ' + p.r._noise; }).forEach(function (g, title) {
        var series = [];
        groupBy(g, function (p) { return p.series; }).forEach(function (sp, name) {
          var byX = groupBy(sp, function (p) { return p.x; });
          var xs = Array.from(byX.keys()).sort(function (a, b) { return a - b; });
          if (xs.length < 2) return;
          series.push({name: name, color: colors[name], line: true, r: 3, pts: xs.map(function (x) {
            var y = mean(byX.get(x).map(function (p) { return p.r[key]; }));
            return [x, y, name + '\n' + title + '\n' + pn + ' ' + fmt(x) + ', ' + key + ' ' + fmt(y)];
          })});
        });
        if (series.length) addPanel(panels, chart({title: title, xlabel: pn, ylabel: key, xlog: positive, ylog: false, series: series}));
      });
    });
  }

  // ------------------------------------------------------------------ main
  var sections = {laplacian: laplacianSection, smoothing: smoothingSection, simplification: simplificationSection};
  Object.keys(D.tasks).forEach(function (task) {
    var d = taskRows(task);
    if (!d) return;
    var host = document.getElementById('plots-' + task);
    if (!host) return;
    guard(task + ' plots', host, function () { (sections[task] || function (x) { genericSection(task, x); })(d); });
    guard(task + ' table', document.getElementById('rows-' + task), function () { rowsTable(task, d); });
  });
  body.dataset.plotsRendered = String(plotsRendered);
  guard('leaderboard', document.getElementById('leaderboard-body'), leaderboardSection);
  guard('3D views', document.getElementById('view-list'), viewsSection);
  body.dataset.plotsRendered = String(plotsRendered);
  body.dataset.ready = '1';
})();
