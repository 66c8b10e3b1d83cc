/* Interactive plots of the jointdb pages, drawn with uPlot (bundled: /ui/static/uplot/).
 *
 * Every <script type="application/json" class="plot-data"> block holds one plot:
 *   {"id", "title", "x": "frequency [Hz]", "y": "|H| [m/N]", "log": true|false, "xlog": false,
 *    "ymin"?: 0, "series": [{"label", "x": [...], "y": [...], "colour", "dash": [...], "fill"?: css colour}]}
 * and is drawn into the element named by its data-target (or a new <div> after it).
 * Drag to zoom (x), double-click or "reset zoom" to zoom out; the legend under the plot
 * reads out the frequency and every series' value at the cursor; buttons switch each axis
 * between linear and logarithmic. No inline code: the page's CSP allows scripts from this
 * server only. window.jointdbPlots.draw(spec, element) draws a spec built by a page script.
 */
(function () {
  "use strict";

  function fmt(v) {
    if (v === null || v === undefined || !isFinite(v)) return "–";
    var a = Math.abs(v);
    if (a !== 0 && (a >= 1e6 || a < 1e-3)) return Number(v.toPrecision(4)).toExponential().replace("e+", "e");
    return String(Number(v.toPrecision(4)));
  }

  function tick(v) { return v === null || v === undefined ? "" : fmt(v); }

  function ticks(log) {  // on a log axis only 1, 2 and 5 times a power of ten are labelled
    return function (u, vals) {
      return vals.map(function (v) {
        if (!log || v === null || v <= 0) return tick(v);
        var m = Math.round(v / Math.pow(10, Math.floor(Math.log10(v) + 1e-9)));
        return (m === 1 || m === 2 || m === 5) ? tick(v) : "";
      });
    };
  }

  function unitOf(label) {
    var m = /\[([^\]]+)\]\s*$/.exec(label || "");
    return m ? m[1] : "";
  }

  function align(spec, ylog) {
    var tables = spec.series.map(function (s) {
      var y = s.y.map(function (v) { return (ylog && v !== null && v <= 0) ? null : v; });
      return [s.x, y];
    });
    return tables.length === 1 ? [tables[0][0], tables[0][1]] : uPlot.join(tables);
  }

  function options(spec, width, ylog, xlog) {
    var xunit = unitOf(spec.x);
    var series = [{label: spec.x, value: function (u, v) { return v === null || v === undefined ? "–" : fmt(v) + " " + xunit; }}];
    spec.series.forEach(function (s) {
      var unit = unitOf(s.label);
      series.push({label: s.label, stroke: s.colour, width: 1.6, dash: s.dash && s.dash.length ? s.dash : undefined,
                   fill: s.fill || undefined, spanGaps: false, points: {show: false},
                   value: function (u, v) { return v === null || v === undefined ? "–" : fmt(v) + (unit ? " " + unit : ""); }});
    });
    return {
      width: width, height: spec.height || 300, series: series,
      scales: {x: {time: false, distr: xlog ? 3 : 1},
               y: spec.ymin === undefined || ylog ? {distr: ylog ? 3 : 1}
                 : {distr: 1, range: function (u, lo, hi) { return [spec.ymin, hi > spec.ymin ? hi * 1.05 : spec.ymin + 1]; }}},
      axes: [{label: spec.x, labelSize: 28, size: 42, values: ticks(xlog)},
             {label: spec.y, labelSize: 28, size: 78, values: ticks(ylog)}],
      cursor: {drag: {x: true, y: false}},
      legend: {live: true}
    };
  }

  function button(text, cls) {
    var b = document.createElement("button");
    b.type = "button";
    b.textContent = text;
    b.className = "plot-button " + cls;
    return b;
  }

  function draw(spec, holder) {
    holder.classList.add("plot");
    holder.id = holder.id || "plot-" + spec.id;
    holder.textContent = "";
    var head = document.createElement("div");
    head.className = "plot-head";
    var title = document.createElement("span");
    title.className = "plot-title";
    title.textContent = spec.title || "";
    var ybtn = button("", "ylog"), xbtn = button("", "xlog"), reset = button("reset zoom", "reset");
    head.append(title, ybtn, xbtn, reset);
    var area = document.createElement("div");
    area.className = "plot-area";
    holder.append(head, area);
    var state = {ylog: !!spec.log, xlog: !!spec.xlog, chart: null};

    function render() {
      if (state.chart) state.chart.destroy();
      var width = Math.max(320, area.clientWidth || holder.clientWidth || 800);
      state.chart = new uPlot(options(spec, width, state.ylog, state.xlog), align(spec, state.ylog), area);
      ybtn.textContent = "y: " + (state.ylog ? "log" : "linear");
      xbtn.textContent = "x: " + (state.xlog ? "log" : "linear");
      holder.dataset.ylog = state.ylog ? "1" : "0";
      holder.dataset.xlog = state.xlog ? "1" : "0";
    }
    ybtn.addEventListener("click", function () { state.ylog = !state.ylog; render(); });
    xbtn.addEventListener("click", function () { state.xlog = !state.xlog; render(); });
    reset.addEventListener("click", function () {
      var xs = state.chart.data[0];
      state.chart.setScale("x", {min: xs[0], max: xs[xs.length - 1]});
    });
    render();
    if (window.ResizeObserver) {
      var last = area.clientWidth;
      new ResizeObserver(function () {
        if (Math.abs(area.clientWidth - last) > 4 && state.chart) {
          last = area.clientWidth;
          state.chart.setSize({width: Math.max(320, last), height: spec.height || 300});
        }
      }).observe(area);
    }
    return state;
  }

  var instances = [];

  function drawAll(root) {
    (root || document).querySelectorAll("script.plot-data").forEach(function (el) {
      var spec = JSON.parse(el.textContent);
      var target = el.dataset.target ? document.getElementById(el.dataset.target) : null;
      if (!target) {
        target = document.createElement("div");
        el.parentNode.insertBefore(target, el.nextSibling);
      }
      instances.push(draw(spec, target));
    });
  }

  window.jointdbPlots = {draw: draw, drawAll: drawAll, fmt: fmt, instances: instances};
  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", function () { drawAll(); });
  else drawAll();
})();
