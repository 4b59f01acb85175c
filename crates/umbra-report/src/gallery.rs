//! The gallery of report.html: every case point × backend as a thumbnail with its status
//! colour, filterable by case, backend and status; a click opens reference | backend | truth |
//! heat map | golden (and the pending golden when insta left one) side by side at full size,
//! with the reason and the command that reproduces the run; a picture that changed from a golden of
//! another driver release, legally, has a dashed outline and says how it changed (`report.html#run=NAME` links to one;
//! `#status=Fail&backend=gles2/zink` presets the filters).
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

/// The gallery section: filters, an empty grid the script fills, the detail view, the data.
pub fn section(results: &[RunResult], pictures: &Path) -> String {
    let mut store = Store::default();
    let mut runs = Vec::with_capacity(results.len());
    let (mut cases, mut backends, mut statuses) =
        (BTreeSet::new(), BTreeSet::new(), BTreeSet::new());
    for r in results {
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
        "pics": store.encoded,
        "runs": runs,
    });
    // Inside a script element: no `<`, `>` or `&` may appear as themselves.
    let data = crate::escape::script_json(&data);
    let options = |all: &str, values: &BTreeSet<String>| {
        let mut s = format!("<option value=\"\">{all}</option>");
        for v in values {
            s.push_str(&format!("<option>{}</option>", esc(v)));
        }
        s
    };
    let statuses: BTreeSet<String> = statuses.into_iter().map(str::to_string).collect();
    format!(
        "<h2 id=\"gallery\">Gallery</h2><p>Every case point on every backend: border colour is the status; \
         click a picture for reference | backend | truth | heat map | golden at full size and the command that \
         reproduces it. {n} runs, {p} distinct pictures.</p>\
         <div class=\"g-filters\"><label>case <select id=\"g-case\">{cases}</select></label> \
         <label>backend <select id=\"g-backend\">{backends}</select></label> \
         <label>status <select id=\"g-status\">{statuses}</select></label> \
         <span id=\"g-count\"></span></div>\
         <div id=\"g-grid\"></div>\
         <div id=\"g-detail\" hidden><div class=\"g-box\"><button id=\"g-close\" type=\"button\">close (Esc)</button>\
         <h3 id=\"g-title\"></h3><p id=\"g-reason\"></p><p>reproduce: <code id=\"g-reproduce\"></code></p><details id=\"g-stderr-box\" hidden><summary>the worker's stderr during the run</summary><pre id=\"g-stderr\"></pre></details>\
         <p id=\"g-repro-line\" hidden>bug report for the driver's developers (reduced case, standalone repro.c, API capture, issue.md): <code id=\"g-repro\"></code></p>\
         <div id=\"g-pictures\"></div></div></div>\
         <script type=\"application/json\" id=\"g-data\">{data}</script><script>{SCRIPT}</script>",
        n = results.len(),
        p = store.encoded.len(),
        cases = options("all", &cases),
        backends = options("all", &backends),
        statuses = options("all", &statuses),
    )
}

/// Styles of the gallery (status colours as in the rest of the page).
pub const STYLE: &str = "#g-grid{display:flex;flex-wrap:wrap;gap:4px;margin:8px 0}\
.cell{width:104px;height:112px;border:3px solid #999;box-sizing:border-box;cursor:pointer;display:flex;flex-direction:column;align-items:center;justify-content:center;font-size:10px;overflow:hidden;background:#fafafa}\
.cell img{max-width:94px;max-height:78px;image-rendering:pixelated}.cell span{white-space:nowrap;overflow:hidden;max-width:94px}\
.cell.Pass{border-color:#2e7d32}.cell.ExpectedFail{border-color:#8bc34a}.cell.Fail,.cell.Crash,.cell.Timeout,.cell.UnexpectedPass{border-color:#c62828}\
.cell.changed{border-style:dashed;outline:2px dashed #1565c0;outline-offset:-6px}.cell[hidden]{display:none}.cell.Skip{border-color:#bbb;color:#777}.cell.Flake{border-color:#ef6c00}\
#g-detail{position:fixed;inset:0;background:rgba(0,0,0,.55);overflow:auto;z-index:10}\
.g-box{background:#fff;margin:24px;padding:12px;border-radius:4px}.g-box figure img{max-width:none}\
.g-filters label{margin-right:12px}";

/// The page's script: builds the grid, lazy-loads thumbnails, filters, opens the detail view.
const SCRIPT: &str = r#"(function () {
  var started = performance.now();
  var data = JSON.parse(document.getElementById('g-data').textContent);
  var grid = document.getElementById('g-grid');
  var uri = function (i) { return 'data:image/png;base64,' + data.pics[i]; };
  var lazy = 'IntersectionObserver' in window ? new IntersectionObserver(function (seen) {
    seen.forEach(function (e) {
      if (e.isIntersecting) { e.target.src = uri(+e.target.dataset.pic); lazy.unobserve(e.target); }
    });
  }, { rootMargin: '300px' }) : null;
  data.runs.forEach(function (r, k) {
    var c = document.createElement('div');
    c.className = 'cell ' + r.s;
    c.dataset.k = k; c.dataset.case = r.c; c.dataset.backend = r.b; c.dataset.status = r.s;
    c.title = r.n + ': ' + r.s;
    if (r.g === 'changed-legal') { c.className += ' changed'; c.title += ' (changed picture, legal on this driver)'; }
    if (r.t !== null) {
      var img = document.createElement('img');
      img.alt = r.n; img.dataset.pic = r.t;
      if (lazy) { lazy.observe(img); } else { img.src = uri(r.t); }
      c.appendChild(img);
    } else {
      var s = document.createElement('span'); s.textContent = r.s; c.appendChild(s);
    }
    var label = document.createElement('span'); label.textContent = r.b; c.appendChild(label);
    var at = r.n.indexOf('@');
    var point = document.createElement('span');
    point.textContent = at < 0 ? r.c : r.c + r.n.slice(at).replace(/^@[^=]*\./, '@');
    c.appendChild(point);
    c.addEventListener('click', function () { open(k); });
    grid.appendChild(c);
  });
  var pick = { case: document.getElementById('g-case'), backend: document.getElementById('g-backend'),
               status: document.getElementById('g-status') };
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
    // What the page really lays out (a style that overrides `hidden` would show them all).
    document.body.dataset.galleryVisible = Array.prototype.filter.call(grid.children, function (c) {
      return c.getClientRects().length > 0;
    }).length;
  }
  Object.keys(pick).forEach(function (f) { pick[f].addEventListener('change', filter); });
  var detail = document.getElementById('g-detail');
  function open(k) {
    var r = data.runs[k];
    document.getElementById('g-title').textContent = r.s + ' ' + r.n;
    document.getElementById('g-reason').textContent = (r.r || '') + (r.d ? ' | consensus: ' + r.d : '') +
      (r.gc ? ' | golden: ' + r.gc : '');
    document.getElementById('g-reproduce').textContent = r.x;
    document.getElementById('g-stderr').textContent = r.e || '';
    document.getElementById('g-stderr-box').hidden = !r.e;
    document.getElementById('g-repro').textContent = r.y || '';
    document.getElementById('g-repro-line').hidden = !r.y;
    var box = document.getElementById('g-pictures');
    box.textContent = '';
    r.p.forEach(function (pic, i) {
      if (pic === null) { return; }
      var f = document.createElement('figure'), img = document.createElement('img'),
          cap = document.createElement('figcaption');
      img.src = uri(pic); img.alt = data.captions[i]; cap.textContent = data.captions[i];
      if (i === 4 && r.g) { cap.textContent += ' (' + r.g + ')'; }
      f.appendChild(img); f.appendChild(cap); box.appendChild(f);
    });
    if (r.p.every(function (p) { return p === null; })) {
      box.textContent = 'No pictures: the run was not rendered and judged (' + r.s + ').';
    }
    detail.hidden = false;
  }
  function close() { detail.hidden = true; }
  document.getElementById('g-close').addEventListener('click', close);
  detail.addEventListener('click', function (e) { if (e.target === detail) { close(); } });
  document.addEventListener('keydown', function (e) { if (e.key === 'Escape') { close(); } });
  // Links: report.html#run=NAME opens one run (also from the page's own tables);
  // #status=Fail&backend=gles2/zink sets filters.
  window.addEventListener('hashchange', function () {
    var h = location.hash.replace(/^#/, '');
    if (h.indexOf('run=') !== 0) { return; }
    var wanted = decodeURIComponent(h.slice(4));
    data.runs.forEach(function (r, k) { if (r.n === wanted) { open(k); } });
  });
  var hash = location.hash.replace(/^#/, '');
  if (hash.indexOf('run=') === 0) {
    var wanted = decodeURIComponent(hash.slice(4));
    data.runs.forEach(function (r, k) { if (r.n === wanted) { open(k); } });
  } else {
    hash.split('&').forEach(function (kv) {
      var p = kv.split('='), f = p[0], v = decodeURIComponent(p.slice(1).join('='));
      if (pick[f]) { pick[f].value = v; }
    });
  }
  filter();
  document.body.dataset.galleryCells = grid.children.length;
  document.body.dataset.galleryMs = Math.round(performance.now() - started);
})();"#;
