/* The page's time cursor (report.html, diff.html): one simulation time shared by the
   videos, every time-series panel and the map. Plain script, no network.
   - videos: video elements with data-t0 (sim time of the file's first frame; sim time =
     t0 + video time)
   - panels: g.t-axis in each svg (data-t0 data-t1 data-x0 data-x1 data-y0 data-y1)
   - map: g.map-frame (data-sx, data-sy: "d0 r0 k", px = r0 + (x - d0) k) and the JSON of
     #srr-tracks (name, kind, run, color, t, x, y)
   - anything with data-seek="t" seeks there on click; data-until="t" then plays to t.
   - a video its server sends whole (no byte ranges: `python -m http.server`) cannot seek;
     it is fetched once and played from memory, and leads nothing until then.
   window.srrCursor = {seek(t), time(), play(), pause()} */
(function () {
  "use strict";
  var bar = document.getElementById("cursor");
  if (!bar) { return; }
  var NS = "http://www.w3.org/2000/svg";
  var EPS = 0.001;  /* a frame shows from its own time on: land just after it */
  var end = parseFloat(bar.getAttribute("data-end")) || 0;
  var videos = Array.prototype.slice.call(document.querySelectorAll("video[data-t0]"));
  var readout = document.getElementById("cursor-time");
  var scrub = document.getElementById("cursor-scrub");
  var playBtn = document.getElementById("cursor-play");
  var T = 0, playing = false, until = null, clockStart = null, raf = null;

  function num(el, name) { return parseFloat(el.getAttribute(name)); }

  var lines = [];
  Array.prototype.forEach.call(document.querySelectorAll("svg g.t-axis"), function (g) {
    var svg = g.ownerSVGElement;
    var ax = {t0: num(g, "data-t0"), t1: num(g, "data-t1"), x0: num(g, "data-x0"),
              x1: num(g, "data-x1")};
    var l = document.createElementNS(NS, "line");
    l.setAttribute("class", "cursor-line");
    l.setAttribute("y1", g.getAttribute("data-y0"));
    l.setAttribute("y2", g.getAttribute("data-y1"));
    svg.appendChild(l);
    svg.addEventListener("click", function (ev) {
      var p = svg.createSVGPoint();
      p.x = ev.clientX; p.y = ev.clientY;
      var q = p.matrixTransform(svg.getScreenCTM().inverse());
      if (q.x < ax.x0 || q.x > ax.x1) { return; }
      seek(ax.t0 + (q.x - ax.x0) / (ax.x1 - ax.x0) * (ax.t1 - ax.t0));
    });
    lines.push({el: l, ax: ax});
  });

  var markers = [];
  var frame = document.querySelector("svg.map g.map-frame");
  var tracksEl = document.getElementById("srr-tracks");
  if (frame && tracksEl) {
    var sx = frame.getAttribute("data-sx").split(" ").map(parseFloat);
    var sy = frame.getAttribute("data-sy").split(" ").map(parseFloat);
    JSON.parse(tracksEl.textContent).forEach(function (tr) {
      if (!tr.t.length) { return; }
      var m = document.createElementNS(NS, "circle");
      m.setAttribute("r", tr.kind === "robot" ? "7" : "5.5");
      m.setAttribute("class", "cursor-marker cursor-" + tr.kind);
      m.setAttribute("data-track", tr.name);
      m.setAttribute("data-run", tr.run);
      m.setAttribute("fill", tr.color);
      frame.ownerSVGElement.appendChild(m);
      markers.push({el: m, tr: tr});
    });
    var at = function (tr, t) {  /* linear between samples, held at both ends */
      var a = 0, b = tr.t.length - 1;
      if (t <= tr.t[0]) { return [tr.x[0], tr.y[0]]; }
      if (t >= tr.t[b]) { return [tr.x[b], tr.y[b]]; }
      while (b - a > 1) { var c = (a + b) >> 1; if (tr.t[c] <= t) { a = c; } else { b = c; } }
      var f = (t - tr.t[a]) / (tr.t[b] - tr.t[a]);
      return [tr.x[a] + f * (tr.x[b] - tr.x[a]), tr.y[a] + f * (tr.y[b] - tr.y[a])];
    };
    markers.forEach(function (m) {
      m.place = function (t) {
        var p = at(m.tr, t);
        m.el.setAttribute("cx", (sx[1] + (p[0] - sx[0]) * sx[2]).toFixed(1));
        m.el.setAttribute("cy", (sy[1] + (p[1] - sy[0]) * sy[2]).toFixed(1));
      };
    });
  }

  function draw() {
    lines.forEach(function (l) {
      var a = l.ax, x = a.x0 + (T - a.t0) / (a.t1 - a.t0) * (a.x1 - a.x0);
      x = Math.max(a.x0, Math.min(a.x1, x));
      l.el.setAttribute("x1", x.toFixed(1));
      l.el.setAttribute("x2", x.toFixed(1));
    });
    markers.forEach(function (m) { m.place(T); });
    if (readout) { readout.textContent = T.toFixed(2) + " s"; }
    if (scrub && document.activeElement !== scrub) { scrub.value = T.toFixed(2); }
    bar.setAttribute("data-time", T.toFixed(3));
  }

  function videoTime(v, t) {
    var d = isFinite(v.duration) ? v.duration : Infinity;
    return Math.max(0, Math.min(d, t - num(v, "data-t0") + EPS));
  }

  function seek(t, keep) {
    T = Math.max(0, Math.min(end || t, t));
    if (!keep) { until = null; }
    videos.forEach(function (v) { v.currentTime = videoTime(v, T); });
    if (playing) { clockStart = {t: T, at: performance.now()}; }
    draw();
  }

  /* whether the video can be put at any time of its file: a server that ignores byte
     ranges (python -m http.server) leaves it seekable over [0, 0] only */
  function seekable(v) {
    var s = v.seekable;
    return s.length > 0 && isFinite(v.duration) && s.end(s.length - 1) >= v.duration - 0.05;
  }

  /* such a video is fetched whole, once, and played from memory (a blob: URL) */
  function fromMemory(v) {
    if (v.hasAttribute("data-memory") || !window.fetch || !window.URL) { return; }
    v.setAttribute("data-memory", "loading");
    fetch(v.currentSrc).then(function (r) {
      if (!r.ok) { throw new Error(String(r.status)); }
      return r.blob();
    }).then(function (b) {
      v.setAttribute("data-memory", "yes");
      v.src = URL.createObjectURL(b);
    }).catch(function () { v.setAttribute("data-memory", "failed"); });
  }

  /* the leading video is the first one still playing; without one, a clock at 1x */
  function leader() {
    for (var i = 0; i < videos.length; i++) {
      var v = videos[i];
      if (!v.paused && !v.ended && seekable(v) && T >= num(v, "data-t0") - EPS) { return v; }
    }
    return null;
  }

  function tick() {
    raf = null;
    if (!playing) { return; }
    var v = leader();
    if (v) {
      T = num(v, "data-t0") + v.currentTime - EPS;
      clockStart = {t: T, at: performance.now()};
    } else if (clockStart) {
      T = clockStart.t + (performance.now() - clockStart.at) / 1000;
      videos.forEach(function (w) {  /* a video whose first frame is now due starts */
        if (w.paused && seekable(w) && T >= num(w, "data-t0")
            && w.currentTime < videoTime(w, T) - 0.2) {
          w.currentTime = videoTime(w, T); w.play().catch(function () {});
        }
      });
    }
    videos.forEach(function (w) {  /* keep the others within a frame or so of the leader */
      if (w !== v && !w.paused && Math.abs(w.currentTime - videoTime(w, T)) > 0.25) {
        w.currentTime = videoTime(w, T);
      }
    });
    if ((until !== null && T >= until) || (end && T >= end)) {
      T = until !== null ? until : end;
      pause();
      return;
    }
    draw();
    raf = requestAnimationFrame(tick);
  }

  function play() {
    if (end && T >= end - 0.01) { seek(0); }
    playing = true;
    clockStart = {t: T, at: performance.now()};
    videos.forEach(function (v) {
      if (!seekable(v)) { return; }  /* it starts once it can be put at the cursor */
      v.currentTime = videoTime(v, T);
      if (T < num(v, "data-t0") - EPS) { return; }
      v.play().catch(function () {});
    });
    if (playBtn) { playBtn.textContent = "❚❚ pause"; }
    bar.classList.add("playing");
    if (raf === null) { raf = requestAnimationFrame(tick); }
  }

  function pause() {
    playing = false;
    videos.forEach(function (v) { v.pause(); });
    if (playBtn) { playBtn.textContent = "▶ play"; }
    bar.classList.remove("playing");
    draw();
  }

  if (playBtn) {
    playBtn.addEventListener("click", function () { if (playing) { pause(); } else { play(); } });
  }
  if (scrub) {
    scrub.addEventListener("input", function () { seek(parseFloat(scrub.value)); });
  }
  var hide = document.getElementById("cursor-hide");
  if (hide) {
    hide.addEventListener("click", function () {
      var small = bar.classList.toggle("collapsed");
      hide.textContent = small ? "show videos" : "hide videos";
    });
  }
  document.addEventListener("click", function (ev) {
    var el = ev.target.closest ? ev.target.closest("[data-seek]") : null;
    if (!el) { return; }
    ev.preventDefault();
    seek(parseFloat(el.getAttribute("data-seek")));
    if (el.hasAttribute("data-until")) {
      until = parseFloat(el.getAttribute("data-until"));
      play();
    }
  });
  videos.forEach(function (v) {
    v.addEventListener("loadedmetadata", function () {
      if (!seekable(v)) { fromMemory(v); return; }
      v.currentTime = videoTime(v, T);
      if (playing && T >= num(v, "data-t0") - EPS) { v.play().catch(function () {}); }
    });
  });
  window.srrCursor = {seek: seek, play: play, pause: pause,
                      time: function () { return T; }};
  draw();
})();
