//! The gallery of report.html: every case point × backend as a thumbnail, failures first, then
//! flakes, expected failures, skips and passes ([`crate::Status::glance_rank`]), each status
//! told by its border's colour, width and style and by a word on the cell, with a legend that
//! counts them and filters by them; names wrap, never cut. Filterable by case, backend and
//! status; a click opens reference | backend | truth | heat map | golden (and the pending golden
//! when insta left one) side by side, with the reason and the command that reproduces the
//! run. The detail view zooms (fit, 1× to 16×, nearest-neighbour pixels, so one texel's error
//! is a block of pixels) and its panels pan together (drag or scroll one, all follow), and
//! sets any other backend's frame of the same point beside this one with their difference
//! (computed in the page, per pixel, its count and largest step said). A picture that changed
//! from a golden of another driver release, legally, has a dashed outline and says how it
//! changed. Links: `report.html#run=NAME` opens a run (`&zoom=4&beside=BACKEND` too);
//! `#status=Fail&backend=gles2/zink` presets the filters.
//!
//! The page stays one self-contained file, sized for the full catalogue:
//! - the grid is built by the page's script from one JSON block, so the HTML itself stays small
//!   and the browser parses no thousands of `<img>` tags up front;
//! - every picture is stored once, by its bytes: the reference and truth of a point are shared by
//!   all its backends, identical frames of two backends (GL 3.3 and GLES 3 on llvmpipe often
//!   agree to the bit) and a golden equal to its frame cost nothing twice;
//! - thumbnails (96 px on the long side) are decoded only when their cell scrolls into view
//!   (IntersectionObserver), full-size pictures only when a cell is opened.
//!
//! Pictures come from the directory the workers wrote them to, one directory per run named by
//! [`crate::names::file_name`] (`thumb.png`, `color.png`, `error.png`, `reference.png`,
//! `truth.png`, `golden.png`, `pending.png`); a run without pictures (a skip, a crash, a
//! timeout) is a cell with its status and reason only.

use std::collections::{BTreeSet, HashMap};
use std::path::Path;

use serde_json::{Value, json};

use crate::escape::{base64, esc};
use crate::model::RunResult;

/// The pictures of a run's detail view, in order: (file, caption).
pub const PICTURES: [(&str, &str); 6] = [
    ("reference.png", "reference"),
    ("color.png", "backend"),
    (
        "truth.png",
        "truth (white lit, grey shadowed, blue tint: edge)",
    ),
    (
        "error.png",
        "heat map (red acne, blue leak, orange/light blue on edges)",
    ),
    ("golden.png", "golden"),
    ("pending.png", "pending golden (cargo insta review)"),
];

/// Pictures stored once each, by content.
#[derive(Default)]
struct Store {
    index: HashMap<Vec<u8>, usize>,
    encoded: Vec<String>,
}

impl Store {
    fn add(&mut self, path: &Path) -> Option<usize> {
        let bytes = std::fs::read(path).ok()?;
        if let Some(i) = self.index.get(&bytes) {
            return Some(*i);
        }
        let i = self.encoded.len();
        self.encoded.push(base64(&bytes));
        self.index.insert(bytes, i);
        Some(i)
    }
}

/// The gallery section: filters, an empty grid the script fills, the detail view, the runs,
/// the script, and then the pictures' block, after the script: the grid, its legend and its
/// filters work as soon as the runs are read, before the browser has read the pictures (52 MB
/// of the catalogue's 54 MB page; reading them is most of a load), and a one-line script after
/// the block hands them to the gallery as soon as they are in.
pub fn section(results: &[RunResult], pictures: &Path) -> String {
    let mut store = Store::default();
    let mut runs = Vec::with_capacity(results.len());
    let (mut cases, mut backends, mut statuses) =
        (BTreeSet::new(), BTreeSet::new(), BTreeSet::new());
    // Failures first (a stable sort: within a status the runs keep the report's order).
    let mut ordered: Vec<&RunResult> = results.iter().collect();
    ordered.sort_by_key(|r| r.status.glance_rank());
    for r in ordered {
        let dir = pictures.join(crate::names::file_name(&r.name));
        let case = r.case.split('@').next().unwrap_or(&r.case).to_string();
        let thumb = store.add(&dir.join("thumb.png"));
        let pics: Vec<Value> = PICTURES
            .iter()
            .map(|(file, _)| json!(store.add(&dir.join(file))))
            .collect();
        cases.insert(case.clone());
        backends.insert(r.backend.clone());
        statuses.insert(r.status.name());
        runs.push(json!({
            "n": r.name,
            "c": case,
            "b": r.backend,
            "s": r.status.name(),
            "t": thumb,
            "p": pics,
            "r": r.reason,
            "d": r.diagnosis.as_ref().map(|d| d.message.clone()),
            "x": r.reproduce,
            "e": (!r.stderr.is_empty()).then(|| r.stderr.clone()),
            // A failed frame's bug report for the driver's developers (`umbra repro`).
            "y": (r.status == crate::model::Status::Fail && r.backend != "ref").then(|| {
                crate::names::repro_command(&r.name, crate::names::mesa_of(&r.reproduce).as_deref())
            }),
            "g": r.golden,
            // How the picture differs from its golden, and between which driver versions.
            "gc": r.metrics.as_ref().and_then(|m| m.golden_change.as_ref()).map(|c| c.describe()),
        }));
    }
    let data = json!({
        "captions": PICTURES.iter().map(|(_, c)| *c).collect::<Vec<_>>(),
        "runs": runs,
    });
    // Inside a script element: no `<`, `>` or `&` may appear as themselves.
    let data = crate::escape::script_json(&data);
    let pictures_block = format!(
        "<script type=\"application/json\" id=\"g-pics\">{}</script>\
         <script>window.umbraGalleryPictures && window.umbraGalleryPictures();</script>",
        crate::escape::script_json(&json!(store.encoded))
    );
    let options = |all: &str, values: &BTreeSet<String>| {
        let mut s = format!("<option value=\"\">{all}</option>");
        for v in values {
            s.push_str(&format!("<option>{}</option>", esc(v)));
        }
        s
    };
    let statuses: BTreeSet<String> = statuses.into_iter().map(str::to_string).collect();
    let html = format!(
        "<h2 id=\"gallery\">Gallery</h2><p>Every case point on every backend, failures first, then flakes, \
         expected failures, skips and passes: the status is the cell's word and its border (legend below, a click \
         on an entry shows that status only). Click a picture for reference | backend | truth | heat map | golden, \
         zoomed with whole pixels, any other backend's frame of the point beside it with their difference, and the \
         command that reproduces it. {n} runs, {p} distinct pictures.</p>\
         <div id=\"g-legend\"></div>\
         <div class=\"g-filters\"><label>case <select id=\"g-case\">{cases}</select></label> \
         <label>backend <select id=\"g-backend\">{backends}</select></label> \
         <label>status <select id=\"g-status\">{statuses}</select></label> \
         <span id=\"g-count\"></span></div>\
         <div id=\"g-grid\"></div>\
         <div id=\"g-detail\" hidden><div class=\"g-box\"><button id=\"g-close\" type=\"button\">close (Esc)</button>\
         <span class=\"g-tools\">zoom <button type=\"button\" data-zoom=\"0\">fit</button><button type=\"button\" data-zoom=\"1\">1×</button>\
         <button type=\"button\" data-zoom=\"2\">2×</button><button type=\"button\" data-zoom=\"4\">4×</button>\
         <button type=\"button\" data-zoom=\"8\">8×</button><button type=\"button\" data-zoom=\"16\">16×</button> (+ and − keys; drag a picture to pan all) \
         <label>beside it <select id=\"g-beside\"></select></label></span>\
         <h3 id=\"g-title\"></h3><p id=\"g-reason\"></p><p>reproduce: <code id=\"g-reproduce\"></code></p><details id=\"g-stderr-box\" hidden><summary>the worker's stderr during the run</summary><pre id=\"g-stderr\"></pre></details>\
         <p id=\"g-repro-line\" hidden>bug report for the driver's developers (reduced case, standalone repro.c, API capture, issue.md): <code id=\"g-repro\"></code></p>\
         <div id=\"g-pictures\"></div></div></div>\
         <script type=\"application/json\" id=\"g-data\">{data}</script><script>{SCRIPT}</script>",
        n = results.len(),
        p = store.encoded.len(),
        cases = options("all", &cases),
        backends = options("all", &backends),
        statuses = options("all", &statuses),
    );
    html + &pictures_block
}

/// Styles of the gallery. A status is told by more than its shade: each has a word on the
/// cell and its own border width and style (failures thick and solid, flakes dashed, expected
/// failures dotted, skips thin grey, passes thin), and the legend shows them with their counts.
pub const STYLE: &str = "#g-grid{display:flex;flex-wrap:wrap;gap:4px;margin:8px 0;align-items:flex-start}\
.cell{content-visibility:auto;contain-intrinsic-size:auto 112px auto 130px;width:112px;min-height:112px;border:2px solid #999;box-sizing:border-box;cursor:pointer;display:flex;flex-direction:column;align-items:center;font-size:10px;background:#fafafa;padding:2px}\
.cell img{max-width:100px;max-height:78px;image-rendering:pixelated}\
.cell span{white-space:normal;overflow-wrap:anywhere;text-align:center;max-width:104px}\
.cell .badge{font-weight:bold;text-transform:uppercase;letter-spacing:.02em}\
.cell.Pass{border:2px solid #2e7d32}.cell.Pass .badge{color:#2e7d32}\
.cell.ExpectedFail{border:3px dotted #558b2f}.cell.ExpectedFail .badge{color:#33691e}\
.cell.Fail,.cell.Crash,.cell.Timeout,.cell.UnexpectedPass,.cell.OrderDependent{border:5px solid #c62828;background:#fff0f0}\
.cell.Fail .badge,.cell.Crash .badge,.cell.Timeout .badge,.cell.UnexpectedPass .badge,.cell.OrderDependent .badge{color:#c62828}\
.cell.Flake{border:4px dashed #ef6c00}.cell.Flake .badge{color:#e65100}\
.cell.Skip{border:1px solid #bbb;color:#666}\
.cell.changed{outline:2px dashed #1565c0;outline-offset:-8px}.cell[hidden]{display:none}\
#g-legend{display:flex;flex-wrap:wrap;gap:6px;margin:6px 0}\
#g-legend button{font-size:12px;background:#fafafa;cursor:pointer;padding:2px 8px}\
#g-legend button.Pass{border:2px solid #2e7d32}#g-legend button.ExpectedFail{border:3px dotted #558b2f}\
#g-legend button.Fail,#g-legend button.Crash,#g-legend button.Timeout,#g-legend button.UnexpectedPass,#g-legend button.OrderDependent{border:5px solid #c62828}\
#g-legend button.Flake{border:4px dashed #ef6c00}#g-legend button.Skip{border:1px solid #bbb}#g-legend button.changed{border:2px dashed #1565c0}\
#g-detail{position:fixed;inset:0;background:rgba(0,0,0,.55);overflow:auto;z-index:10}\
.g-box{background:#fff;margin:24px;padding:12px;border-radius:4px}\
.g-tools{margin-left:12px}.g-tools button.on{font-weight:bold;background:#1565c0;color:#fff}\
#g-pictures{display:flex;flex-wrap:wrap;gap:8px}#g-pictures figure{margin:0}\
.g-pane{overflow:auto;max-width:46vw;max-height:62vh;border:1px solid #ccc;cursor:grab}\
.g-pane img,.g-pane canvas{image-rendering:pixelated;display:block;max-width:none;border:0}\
.g-pane img.fit,.g-pane canvas.fit{max-width:100%}\
.g-filters label{margin-right:12px}";

/// The page's script: builds the grid (failures first, as the data comes) and its legend,
/// lazy-loads thumbnails, filters, opens the detail view, zooms and pans it, and sets another
/// backend's frame beside the open one with their difference.
const SCRIPT: &str = r#"(function () {
  var started = performance.now();
  var data = JSON.parse(document.getElementById('g-data').textContent);
  document.body.dataset.galleryParseMs = Math.round(performance.now() - started);
  var grid = document.getElementById('g-grid');
  // The pictures' block comes at the page's end: read once, when the page has it.
  var pics = null;
  var uri = function (i) {
    if (pics === null) {
      // Not before the parser has read the whole block (a script element grows as it is
      // read): the line after it says when.
      if (!picturesIn) { return ''; }
      var el = document.getElementById('g-pics');
      pics = el ? JSON.parse(el.textContent) : [];
    }
    return 'data:image/png;base64,' + (pics[i] || '');
  };
  var WORD = { Fail: 'fail', Crash: 'crash', Timeout: 'timeout', UnexpectedPass: 'unexpected pass',
               OrderDependent: 'order-dependent', Flake: 'flake', ExpectedFail: 'expected fail',
               Skip: 'skip', Pass: 'pass' };
  var ORDER = ['Fail', 'Crash', 'Timeout', 'UnexpectedPass', 'OrderDependent', 'Flake',
               'ExpectedFail', 'Skip', 'Pass'];
  var thumbs = [];
  var lazy = 'IntersectionObserver' in window ? new IntersectionObserver(function (seen) {
    seen.forEach(function (e) {
      if (e.isIntersecting) { e.target.src = uri(+e.target.dataset.pic); lazy.unobserve(e.target); }
    });
  }, { rootMargin: '300px' }) : null;
  var counts = {}, changed = 0;
  // A run's point: its name without the backend (`BACKEND/CASE@POINT`).
  var point = function (r) { return r.n.slice(r.b.length + 1); };
  var byPoint = {};
  var cells = document.createDocumentFragment();
  data.runs.forEach(function (r, k) {
    counts[r.s] = (counts[r.s] || 0) + 1;
    (byPoint[point(r)] = byPoint[point(r)] || []).push(k);
    var c = document.createElement('div');
    c.className = 'cell ' + r.s;
    c.dataset.k = k; c.dataset.case = r.c; c.dataset.backend = r.b; c.dataset.status = r.s;
    c.title = r.n + ': ' + (WORD[r.s] || r.s);
    if (r.g === 'changed-legal') {
      c.className += ' changed'; changed++;
      c.title += ' (changed picture, legal on this driver)';
    }
    var badge = document.createElement('span'); badge.className = 'badge';
    badge.textContent = (WORD[r.s] || r.s) + (r.g === 'changed-legal' ? ', changed' : '');
    c.appendChild(badge);
    if (r.t !== null) {
      var img = document.createElement('img');
      img.alt = r.n; img.dataset.pic = r.t;
      thumbs.push(img);
      c.appendChild(img);
    }
    var label = document.createElement('span'); label.className = 'name'; label.textContent = r.b; c.appendChild(label);
    var at = r.n.indexOf('@');
    var pt = document.createElement('span'); pt.className = 'name';
    pt.textContent = at < 0 ? r.c : r.c + r.n.slice(at).replace(/^@[^=]*\./, '@');
    c.appendChild(pt);
    cells.appendChild(c);
  });
  grid.appendChild(cells);
  // One listener for every cell.
  grid.addEventListener('click', function (e) {
    var c = e.target.closest('.cell');
    if (c) { open(+c.dataset.k); }
  });
  var pick = { case: document.getElementById('g-case'), backend: document.getElementById('g-backend'),
               status: document.getElementById('g-status') };
  // The legend: every status present, in the gallery's order, with its count; a click filters.
  var legend = document.getElementById('g-legend');
  ORDER.forEach(function (st) {
    if (!counts[st]) { return; }
    var b = document.createElement('button');
    b.type = 'button'; b.className = st; b.dataset.status = st;
    b.textContent = WORD[st] + ' ' + counts[st];
    b.addEventListener('click', function () {
      pick.status.value = pick.status.value === st ? '' : st; filter(); setTimeout(measure, 0);
    });
    legend.appendChild(b);
  });
  if (changed) {
    var ch = document.createElement('span'); ch.className = 'changed';
    ch.textContent = 'dashed blue outline: a picture changed from another release\u2019s golden, legal on this driver (' + changed + ')';
    legend.appendChild(ch);
  }
  var count = document.getElementById('g-count');
  function filter() {
    var shown = 0;
    Array.prototype.forEach.call(grid.children, function (c) {
      var ok = ['case', 'backend', 'status'].every(function (f) {
        return pick[f].value === '' || c.dataset[f] === pick[f].value;
      });
      c.hidden = !ok; if (ok) { shown++; }
    });
    count.textContent = shown + ' of ' + grid.children.length + ' runs shown';
    document.body.dataset.galleryShown = shown;
    measured = false;
  }
  // What the page really lays out (a style that overrides `hidden` would show them all) and
  // whether a shown name overflows its cell, measured after the page is drawn (reading layout
  // inside the filter would lay the whole grid out before the first paint).
  var measured = false;
  function measure() {
    if (measured) { return; }
    measured = true;
    document.body.dataset.galleryVisible = Array.prototype.filter.call(grid.children, function (c) {
      return c.getClientRects().length > 0;
    }).length;
    // The first 300 shown cells: what a screen holds (the rest are not laid out until they
    // scroll into view, `content-visibility: auto`, and are styled the same).
    document.body.dataset.galleryClipped = Array.prototype.slice.call(grid.querySelectorAll('.cell:not([hidden])'), 0, 300)
      .reduce(function (n, c) {
        return n + Array.prototype.filter.call(c.querySelectorAll('span'), function (s) {
          return s.scrollWidth > s.clientWidth + 1;
        }).length;
      }, 0);
  }
  Object.keys(pick).forEach(function (f) {
    pick[f].addEventListener('change', function () { filter(); setTimeout(measure, 0); });
  });
  var detail = document.getElementById('g-detail');
  var zoom = 0, current = null;
  var beside = document.getElementById('g-beside');
  var zoomButtons = Array.prototype.slice.call(document.querySelectorAll('.g-tools button'));
  function applyZoom() {
    Array.prototype.forEach.call(document.querySelectorAll('#g-pictures img, #g-pictures canvas'), function (im) {
      var w = im.naturalWidth || im.width;
      if (zoom === 0 || !w) { im.classList.add('fit'); im.style.width = ''; }
      else { im.classList.remove('fit'); im.style.width = (w * zoom) + 'px'; }
    });
    zoomButtons.forEach(function (b) { b.classList.toggle('on', +b.dataset.zoom === zoom); });
    document.body.dataset.galleryZoom = zoom;
    // The width the first picture is drawn at (a style that capped it would show here).
    var first = document.querySelector('#g-pictures img');
    if (first && first.naturalWidth) {
      document.body.dataset.galleryDrawnWidth = Math.round(first.getBoundingClientRect().width);
    }
  }
  function setZoom(z) { zoom = z; applyZoom(); }
  zoomButtons.forEach(function (b) { b.addEventListener('click', function () { setZoom(+b.dataset.zoom); }); });
  // The panels pan together: scrolling or dragging one moves every other to the same place.
  var syncing = false;
  function follow(src) {
    if (syncing) { return; }
    syncing = true;
    Array.prototype.forEach.call(document.querySelectorAll('.g-pane'), function (p) {
      if (p !== src) { p.scrollLeft = src.scrollLeft; p.scrollTop = src.scrollTop; }
    });
    syncing = false;
  }
  function pane(content, caption) {
    var f = document.createElement('figure'), p = document.createElement('div'),
        cap = document.createElement('figcaption');
    p.className = 'g-pane'; p.appendChild(content); cap.textContent = caption;
    p.addEventListener('scroll', function () { follow(p); });
    var drag = null;
    p.addEventListener('mousedown', function (e) { drag = [e.clientX, e.clientY, p.scrollLeft, p.scrollTop]; e.preventDefault(); });
    window.addEventListener('mouseup', function () { drag = null; });
    p.addEventListener('mousemove', function (e) {
      if (drag) { p.scrollLeft = drag[2] - (e.clientX - drag[0]); p.scrollTop = drag[3] - (e.clientY - drag[1]); }
    });
    f.appendChild(p); f.appendChild(cap);
    return f;
  }
  function picture(i, caption) {
    var img = document.createElement('img');
    img.addEventListener('load', applyZoom);
    img.src = uri(i); img.alt = caption;
    return pane(img, caption);
  }
  // The difference of two frames, per pixel: grey where they agree (the frame, dimmed), red
  // where any channel differs (brighter the larger the step); its count and largest step.
  function difference(a, b, caption) {
    var c = document.createElement('canvas'), f = pane(c, caption), cap = f.querySelector('figcaption');
    var ia = new Image(), ib = new Image(), loaded = 0;
    function pixels(im, w, h) {
      var t = document.createElement('canvas'); t.width = w; t.height = h;
      var x = t.getContext('2d'); x.drawImage(im, 0, 0);
      return x.getImageData(0, 0, w, h).data;
    }
    function done() {
      if (++loaded < 2) { return; }
      var w = ia.naturalWidth, h = ia.naturalHeight;
      if (w !== ib.naturalWidth || h !== ib.naturalHeight) {
        cap.textContent = caption + ': the frames differ in size';
        return;
      }
      c.width = w; c.height = h;
      var da = pixels(ia, w, h), db = pixels(ib, w, h);
      var x = c.getContext('2d'), out = x.createImageData(w, h), n = 0, most = 0;
      for (var i = 0; i < da.length; i += 4) {
        var d = Math.max(Math.abs(da[i] - db[i]), Math.abs(da[i + 1] - db[i + 1]),
                         Math.abs(da[i + 2] - db[i + 2]), Math.abs(da[i + 3] - db[i + 3]));
        var grey = (da[i] + da[i + 1] + da[i + 2]) / 12;
        if (d > 0) { n++; most = Math.max(most, d); }
        out.data[i] = d > 0 ? Math.min(255, 128 + 16 * d) : grey;
        out.data[i + 1] = d > 0 ? 0 : grey;
        out.data[i + 2] = d > 0 ? 0 : grey;
        out.data[i + 3] = 255;
      }
      x.putImageData(out, 0, 0);
      cap.textContent = caption + ': ' + n + ' px differ' + (n ? ', largest step ' + most + '/255' : '');
      document.body.dataset.galleryDiffPx = n;
      document.body.dataset.galleryDiffStep = most;
      applyZoom();
    }
    ia.onload = done; ib.onload = done;
    ia.src = uri(a); ib.src = uri(b);
    return f;
  }
  function showBeside() {
    var r = data.runs[current], box = document.getElementById('g-beside-box');
    box.textContent = '';
    var k = beside.value === '' ? -1 : +beside.value;
    document.body.dataset.galleryBeside = k < 0 ? '' : data.runs[k].b;
    if (k < 0) { return; }
    var o = data.runs[k];
    box.appendChild(picture(o.p[1], 'beside: ' + o.b + ' (' + (WORD[o.s] || o.s) + ')'));
    box.appendChild(difference(r.p[1], o.p[1], 'difference, ' + r.b + ' against ' + o.b));
  }
  beside.addEventListener('change', showBeside);
  function open(k, opts) {
    opts = opts || {};
    current = k;
    var r = data.runs[k];
    document.getElementById('g-title').textContent = (WORD[r.s] || r.s) + ': ' + r.n;
    document.getElementById('g-reason').textContent = (r.r || '') + (r.d ? ' | consensus: ' + r.d : '') +
      (r.gc ? ' | golden: ' + r.gc : '');
    document.getElementById('g-reproduce').textContent = r.x;
    document.getElementById('g-stderr').textContent = r.e || '';
    document.getElementById('g-stderr-box').hidden = !r.e;
    document.getElementById('g-repro').textContent = r.y || '';
    document.getElementById('g-repro-line').hidden = !r.y;
    var box = document.getElementById('g-pictures');
    box.textContent = '';
    // Another backend's frame and the difference go right after this run's own frame.
    var extra = document.createElement('div'); extra.id = 'g-beside-box'; extra.style.display = 'contents';
    r.p.forEach(function (pic, i) {
      if (pic === null) { return; }
      var cap = data.captions[i];
      if (i === 4 && r.g) { cap += ' (' + r.g + ')'; }
      box.appendChild(picture(pic, cap));
      if (i === 1) { box.appendChild(extra); }
    });
    if (r.p.every(function (p) { return p === null; })) {
      box.textContent = 'No pictures: the run was not rendered and judged (' + r.s + ').';
    }
    if (!extra.parentNode) { box.appendChild(extra); }
    // Any other backend's frame of the same point.
    beside.textContent = '';
    var none = document.createElement('option'); none.value = ''; none.textContent = 'nothing'; beside.appendChild(none);
    (byPoint[point(r)] || []).forEach(function (o) {
      if (o === k || data.runs[o].p[1] === null || r.p[1] === null) { return; }
      var opt = document.createElement('option'); opt.value = o;
      opt.textContent = data.runs[o].b + ' (' + (WORD[data.runs[o].s] || data.runs[o].s) + ')';
      if (opts.beside === data.runs[o].b) { opt.selected = true; }
      beside.appendChild(opt);
    });
    showBeside();
    setZoom(opts.zoom === undefined ? zoom : opts.zoom);
    detail.hidden = false;
  }
  function close() { detail.hidden = true; }
  document.getElementById('g-close').addEventListener('click', close);
  detail.addEventListener('click', function (e) { if (e.target === detail) { close(); } });
  document.addEventListener('keydown', function (e) {
    if (e.key === 'Escape') { close(); }
    if (detail.hidden) { return; }
    var steps = [0, 1, 2, 4, 8, 16], at = steps.indexOf(zoom);
    if (e.key === '+' || e.key === '=') { setZoom(steps[Math.min(steps.length - 1, at + 1)]); }
    if (e.key === '-') { setZoom(steps[Math.max(0, at - 1)]); }
  });
  // Links: report.html#run=NAME opens one run (also from the page's own tables), with
  // &zoom=Z and &beside=BACKEND; #status=Fail&backend=gles2/zink sets filters.
  function follow_link(h) {
    if (h.indexOf('run=') !== 0) { return false; }
    var opts = {}, parts = h.split('&'), wanted = decodeURIComponent(parts[0].slice(4));
    parts.slice(1).forEach(function (kv) {
      var p = kv.split('='), v = decodeURIComponent(p.slice(1).join('='));
      if (p[0] === 'zoom') { opts.zoom = +v; }
      if (p[0] === 'beside') { opts.beside = v; }
    });
    data.runs.forEach(function (r, k) { if (r.n === wanted) { open(k, opts); } });
    return true;
  }
  window.addEventListener('hashchange', function () { follow_link(location.hash.replace(/^#/, '')); });
  var hash = location.hash.replace(/^#/, '');
  if (hash.indexOf('run=') !== 0) {
    hash.split('&').forEach(function (kv) {
      var p = kv.split('='), f = p[0], v = decodeURIComponent(p.slice(1).join('='));
      if (pick[f]) { pick[f].value = v; }
    });
  }
  // Pictures (thumbnails as their cells scroll into view, a linked run's detail) once the
  // page has read its pictures' block.
  function withPictures() {
    thumbs.forEach(function (img) { if (lazy) { lazy.observe(img); } else { img.src = uri(+img.dataset.pic); } });
    follow_link(hash);
    document.body.dataset.galleryPicturesMs = Math.round(performance.now());
  }
  var picturesIn = false;
  window.umbraGalleryPictures = function () { picturesIn = true; withPictures(); };
  filter();
  document.body.dataset.galleryCells = grid.children.length;
  document.body.dataset.galleryMs = Math.round(performance.now() - started);
  // From the page's start (its HTML and data parsed too) to a gallery ready to use.
  document.body.dataset.galleryReadyMs = Math.round(performance.now());
  setTimeout(measure, 0);
})();"#;
