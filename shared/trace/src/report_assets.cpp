#include "report_assets.hpp"

namespace openvcu::trace {

std::string_view reportStyle() noexcept {
  return R"css(
body{font-family:"DejaVu Sans",Verdana,sans-serif;font-size:14px;color:#222;background:#fff;margin:20px 24px}
h1{font-size:22px;margin:0 0 4px}
h2{font-size:18px;border-bottom:1px solid #ccc;padding-bottom:3px;margin:28px 0 8px}
h3{font-size:15px;margin:16px 0 4px}
.source{color:#555;margin:0 0 8px}
.summary td{text-align:left}
nav a{margin-right:14px}
.hint{color:#555;font-size:12px}
table{border-collapse:collapse;font-size:12px;margin:6px 0}
th,td{border:1px solid #ccc;padding:2px 6px;text-align:right;white-space:nowrap}
th{background:#f0f0f0;position:sticky;top:0}
td.l,th.l{text-align:left}
td.w{white-space:normal;max-width:760px}
.tablewrap{max-height:320px;overflow:auto;display:inline-block;max-width:100%}
figure{margin:10px 0 14px}
figcaption{font-size:13px;color:#444;max-width:1300px;margin-top:2px}
.chart{display:inline-block;max-width:100%;overflow-x:auto;vertical-align:top}
svg.tsvg{cursor:grab;touch-action:none;-webkit-user-select:none;user-select:none}
.nodata{color:#777;font-style:italic}
.sev-fault{color:#b03a00;font-weight:bold}
.sev-warning{color:#8a5a00}
@media print{.tablewrap{max-height:none;overflow:visible}}
)css";
}

std::string_view reportScript() noexcept {
  // Zoom/pan: every svg.tsvg has data-t0/-t1 (its time range) and data-l/-w (its plot
  // area in px). A view [v0, v1] maps a drawn x to a*x+b; groups .zx get that transform,
  // elements with data-x are moved (and their labels hidden when they would overlap),
  // groups .xa get new ticks. A URL ending in #view=T0,T1 opens with that range.
  return R"js(
(function () {
  'use strict';
  var charts = Array.prototype.slice.call(document.querySelectorAll('svg.tsvg'));
  var full = null;
  charts.forEach(function (svg) {
    var a = +svg.getAttribute('data-t0'), b = +svg.getAttribute('data-t1');
    full = full ? [Math.min(full[0], a), Math.max(full[1], b)] : [a, b];
  });
  var view = full ? full.slice() : null;

  function el(svg, name, attrs, text) {
    var e = document.createElementNS(svg.namespaceURI, name);
    for (var k in attrs) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    return e;
  }
  function niceStep(span, n) {
    var raw = span / n, mag = Math.pow(10, Math.floor(Math.log(raw) / Math.LN10)), r = raw / mag;
    return (r <= 1 ? 1 : r <= 2 ? 2 : r <= 5 ? 5 : 10) * mag;
  }
  function decimals(step) {
    return Math.max(0, -Math.floor(Math.log(step) / Math.LN10 + 1e-9));
  }
  function clamp(v) {
    var fullSpan = full[1] - full[0];
    var span = Math.max(Math.min(v[1] - v[0], fullSpan), fullSpan * 1e-6);
    var a = Math.max(full[0], Math.min(v[0], full[1] - span));
    return [a, a + span];
  }
  function apply() {
    var span = view[1] - view[0];
    charts.forEach(function (svg) {
      var t0 = +svg.getAttribute('data-t0'), t1 = +svg.getAttribute('data-t1');
      var L = +svg.getAttribute('data-l'), W = +svg.getAttribute('data-w');
      var a = (t1 - t0) / span;
      var b = L + (t0 - view[0]) / span * W - a * L;
      svg.querySelectorAll('.zx').forEach(function (g) {
        g.setAttribute('transform', 'matrix(' + a + ' 0 0 1 ' + b + ' 0)');
      });
      var lanes = {};
      svg.querySelectorAll('[data-x]').forEach(function (e) {
        var x = a * +e.getAttribute('data-x') + b, key, label, offset;
        if (e.tagName === 'g') {
          var y = +e.getAttribute('data-y');
          e.setAttribute('transform', 'translate(' + x + ' ' + y + ')');
          label = e.querySelector('text');
          key = 'e' + y;
          offset = 7;
        } else {
          // an interval's label: at its start, or at the left edge while the interval goes on
          if (x < L && a * +e.getAttribute('data-e') + b > L) x = L;
          e.setAttribute('x', x + 3);
          label = e;
          key = 'l' + e.getAttribute('y');
          offset = 3;
        }
        (lanes[key] = lanes[key] || []).push({x: x, start: x + offset, label: label});
      });
      // the rule of labelsShown() in svg_chart.cpp: inside the plot, after the previous label,
      // before the next anchor
      Object.keys(lanes).forEach(function (key) {
        var items = lanes[key], end = -Infinity;
        items.forEach(function (item, k) {
          if (!item.label) return;
          var labelEnd = item.start + item.label.textContent.length * 6.5;
          if (item.start >= L && labelEnd <= L + W && item.start >= end + 4 &&
              (k + 1 === items.length || items[k + 1].x - 6 > labelEnd)) {
            item.label.removeAttribute('display');
            end = labelEnd;
          } else {
            item.label.setAttribute('display', 'none');
          }
        });
      });
      svg.querySelectorAll('.xa').forEach(function (g) {
        while (g.firstChild) g.removeChild(g.firstChild);
        var y0 = +g.getAttribute('data-y0'), y1 = +g.getAttribute('data-y1');
        var step = niceStep(span, 10), d = decimals(step);
        for (var i = Math.ceil(view[0] / step - 1e-9); i * step <= view[1] + step * 1e-9; ++i) {
          var x = L + (i * step - view[0]) / span * W;
          g.appendChild(el(svg, 'line', {x1: x, x2: x, y1: y0, y2: y1, stroke: '#dddddd'}));
          g.appendChild(el(svg, 'text', {x: x, y: y1 + 15, 'text-anchor': 'middle', fill: '#222222'},
                           (i * step).toFixed(d)));
        }
      });
    });
    var range = document.getElementById('view-range');
    if (range) {
      var d = decimals(niceStep(span, 10)) + 1;
      range.textContent = 'showing ' + view[0].toFixed(d) + ' s to ' + view[1].toFixed(d) + ' s';
    }
  }
  function timeAt(svg, clientX) {
    var r = svg.getBoundingClientRect();
    var px = (clientX - r.left) * svg.viewBox.baseVal.width / r.width;
    var L = +svg.getAttribute('data-l'), W = +svg.getAttribute('data-w');
    return view[0] + (px - L) / W * (view[1] - view[0]);
  }
  charts.forEach(function (svg) {
    svg.addEventListener('wheel', function (e) {
      e.preventDefault();
      var t = timeAt(svg, e.clientX);
      var k = Math.pow(1.0015, e.deltaY * (e.deltaMode === 1 ? 30 : 1));
      view = clamp([t - (t - view[0]) * k, t + (view[1] - t) * k]);
      apply();
    }, {passive: false});
    var drag = null;
    svg.addEventListener('pointerdown', function (e) {
      drag = {x: e.clientX, view: view.slice(), t: timeAt(svg, e.clientX)};
      svg.setPointerCapture(e.pointerId);
      svg.style.cursor = 'grabbing';
    });
    svg.addEventListener('pointermove', function (e) {
      if (!drag) return;
      var saved = view;
      view = drag.view;
      var dt = timeAt(svg, e.clientX) - drag.t;
      view = clamp([drag.view[0] - dt, drag.view[1] - dt]);
      if (view[0] !== saved[0] || view[1] !== saved[1]) apply();
    });
    function end() { drag = null; svg.style.cursor = ''; }
    svg.addEventListener('pointerup', end);
    svg.addEventListener('pointercancel', end);
    svg.addEventListener('dblclick', function () { view = full.slice(); apply(); });
  });
  // report.html#view=300,320 opens with that time range
  var wanted = /view=(-?[0-9.e+-]+),(-?[0-9.e+-]+)/.exec(window.location.hash);
  if (view && wanted && +wanted[2] > +wanted[1]) view = clamp([+wanted[1], +wanted[2]]);
  if (view) apply();

  function layout() {
    var list = [];
    document.querySelectorAll('.chart').forEach(function (c) {
      var r = c.getBoundingClientRect();
      list.push({id: c.getAttribute('data-chart'), x: Math.round(r.left + window.scrollX),
                 y: Math.round(r.top + window.scrollY), w: Math.round(r.width), h: Math.round(r.height)});
    });
    var page = document.documentElement;
    document.getElementById('chart-layout').textContent =
        JSON.stringify({page: {w: page.scrollWidth, h: page.scrollHeight}, charts: list});
  }
  layout();
  window.addEventListener('load', layout);
})();
)js";
}

}  // namespace openvcu::trace
