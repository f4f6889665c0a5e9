/* bladelab runner animation: a stick figure drawn in inline SVG from the frame data in the
   block's <script type="application/json" class="anim-data">. No external resources.
   Each block calls window.bladelabRunnerAnimation(rootElement) once; the root element's
   data-frame attribute holds the frame shown (read by the tests). */
(function () {
  "use strict";
  if (window.bladelabRunnerAnimation) { return; }
  var NS = "http://www.w3.org/2000/svg";
  var COLORS = {
    l: "#1f5fa8", r: "#c0392b", trunk: "#3b4252", head: "#3b4252", blade: "#e67e22",
    grf: "#2e8b57", ground: "#6b7280"
  };
  var WIDTHS = {l: 4, r: 4, trunk: 5, head: 3, blade: 5};

  function el(name, attrs, parent) {
    var node = document.createElementNS(NS, name);
    for (var key in attrs) { node.setAttribute(key, attrs[key]); }
    if (parent) { parent.appendChild(node); }
    return node;
  }

  function init(root) {
    var data = JSON.parse(root.querySelector("script.anim-data").textContent);
    var n = data.n, np = data.np;
    var W = 760, H = 400, S = 170, GY = 350;
    var stage = root.querySelector(".anim-stage");
    var svg = el("svg", {viewBox: "0 0 " + W + " " + H, width: "100%", role: "img",
                         "aria-label": "animated runner: " + data.label}, stage);
    svg.style.maxWidth = "900px";
    svg.style.background = "#fbfcfe";
    svg.style.border = "1px solid #dde2ea";
    svg.style.borderRadius = "6px";
    el("line", {x1: 0, y1: GY, x2: W, y2: GY, stroke: COLORS.ground, "stroke-width": 2}, svg);
    var ticks = [], spacing = 0.5, nticks = Math.ceil(W / S / spacing) + 2;
    for (var i = 0; i < nticks; i++) {
      var g = el("g", {}, svg);
      el("line", {x1: 0, y1: GY, x2: 0, y2: GY + 8, stroke: COLORS.ground, "stroke-width": 1.5}, g);
      var txt = el("text", {x: 0, y: GY + 24, "font-size": 12, "text-anchor": "middle",
                            fill: COLORS.ground}, g);
      ticks.push({g: g, text: txt});
    }
    var shapes = data.edges.map(function (e) {
      return el("line", {stroke: COLORS[e[2]] || "#333", "stroke-width": WIDTHS[e[2]] || 3,
                         "stroke-linecap": "round"}, svg);
    });
    var rings = data.circles.map(function (c) {
      if (c[3]) {
        return el("polyline", {fill: "none", stroke: COLORS[c[2]] || "#333",
                               "stroke-width": WIDTHS[c[2]] || 3, "stroke-linecap": "round"}, svg);
      }
      return el("circle", {fill: c[2] === "head" ? "#e5e9f0" : "none",
                           stroke: COLORS[c[2]] || "#333", "stroke-width": 2}, svg);
    });
    var arrows = data.legs.map(function () {
      var g = el("g", {}, svg);
      return {g: g,
              line: el("line", {stroke: COLORS.grf, "stroke-width": 3}, g),
              head: el("polygon", {fill: COLORS.grf}, g)};
    });
    var clock = el("text", {x: 12, y: 22, "font-size": 14, fill: "#1d2330"}, svg);
    // the key goes under the clock: beside it, a long title ran into it
    var key = el("text", {x: 12, y: 40, "font-size": 12, fill: "#5b6475"}, svg);
    key.textContent = data.legs[0] + " leg blue, " + data.legs[1] + " leg red" +
      (data.has_blade ? ", blade orange" : "") + "; GRF green (1 BW = " + data.bw_length_m + " m)";

    var button = root.querySelector("button.anim-play");
    var slider = root.querySelector("input.anim-slider");
    var speedBox = root.querySelector("select.anim-speed");
    var readout = root.querySelector(".anim-time");
    slider.max = String(n - 1);
    var frame = 0, playing = false, last = null, acc = 0;

    function px(k, j) { return data.P[(k * np + j) * 2] / 1000; }
    function pz(k, j) { return data.P[(k * np + j) * 2 + 1] / 1000; }

    function draw(k) {
      frame = k;
      var cam = px(k, 0);
      var X = function (x) { return (x - cam) * S + W / 2; };
      var Y = function (z) { return GY - z * S; };
      var first = Math.floor((cam - W / 2 / S) / spacing) * spacing;
      ticks.forEach(function (t, i) {
        var x = first + i * spacing;
        t.g.setAttribute("transform", "translate(" + X(x).toFixed(1) + ",0)");
        t.text.textContent = Math.abs(x - Math.round(x)) < 1e-6 ? Math.round(x) + " m" : "";
      });
      data.edges.forEach(function (e, i) {
        shapes[i].setAttribute("x1", X(px(k, e[0])).toFixed(1));
        shapes[i].setAttribute("y1", Y(pz(k, e[0])).toFixed(1));
        shapes[i].setAttribute("x2", X(px(k, e[1])).toFixed(1));
        shapes[i].setAttribute("y2", Y(pz(k, e[1])).toFixed(1));
      });
      data.circles.forEach(function (c, i) {
        var cx = px(k, c[0]), cz = pz(k, c[0]), r = c[1] / 1000;
        if (c[3]) {
          var pts = [];
          for (var a = 200; a <= 340; a += 10) {
            var rad = a * Math.PI / 180;
            pts.push(X(cx + r * Math.cos(rad)).toFixed(1) + "," + Y(cz + r * Math.sin(rad)).toFixed(1));
          }
          rings[i].setAttribute("points", pts.join(" "));
        } else {
          rings[i].setAttribute("cx", X(cx).toFixed(1));
          rings[i].setAttribute("cy", Y(cz).toFixed(1));
          rings[i].setAttribute("r", (r * S).toFixed(1));
        }
      });
      arrows.forEach(function (a, leg) {
        var o = (k * data.legs.length + leg) * 3;
        var x0 = data.G[o] / 1000, fx = data.G[o + 1], fz = data.G[o + 2];
        var f = Math.sqrt(fx * fx + fz * fz);
        if (f < 1) { a.g.setAttribute("visibility", "hidden"); return; }
        a.g.setAttribute("visibility", "visible");
        var scale = data.bw_length_m / data.bw;
        var x1 = X(x0), y1 = Y(0), x2 = X(x0 + fx * scale), y2 = Y(fz * scale);
        a.line.setAttribute("x1", x1.toFixed(1)); a.line.setAttribute("y1", y1.toFixed(1));
        a.line.setAttribute("x2", x2.toFixed(1)); a.line.setAttribute("y2", y2.toFixed(1));
        var ux = (x2 - x1) / Math.hypot(x2 - x1, y2 - y1), uy = (y2 - y1) / Math.hypot(x2 - x1, y2 - y1);
        var hx = x2 + 10 * ux, hy = y2 + 10 * uy;
        a.head.setAttribute("points", hx.toFixed(1) + "," + hy.toFixed(1) + " " +
          (x2 - 5 * uy).toFixed(1) + "," + (y2 + 5 * ux).toFixed(1) + " " +
          (x2 + 5 * uy).toFixed(1) + "," + (y2 - 5 * ux).toFixed(1));
      });
      var t = data.t[k];
      clock.textContent = data.label + "   t = " + t.toFixed(3) + " s";
      readout.textContent = "t = " + t.toFixed(3) + " s (frame " + (k + 1) + " of " + n + ")";
      slider.value = String(k);
      root.setAttribute("data-frame", String(k));
    }

    function tick(ts) {
      if (!playing) { return; }
      if (last !== null) {
        acc += (ts - last) / 1000 * parseFloat(speedBox.value);
        var steps = Math.floor(acc / data.dt);
        if (steps > 0) { acc -= steps * data.dt; draw((frame + steps) % n); }
      }
      last = ts;
      window.requestAnimationFrame(tick);
    }

    function setPlaying(on) {
      playing = on;
      last = null;
      acc = 0;
      button.textContent = on ? "Pause" : "Play";
      root.setAttribute("data-playing", on ? "yes" : "no");
      if (on) { window.requestAnimationFrame(tick); }
    }

    button.addEventListener("click", function () { setPlaying(!playing); });
    slider.addEventListener("input", function () { draw(parseInt(slider.value, 10)); });
    draw(0);
    setPlaying(false);
  }

  window.bladelabRunnerAnimation = init;
})();
