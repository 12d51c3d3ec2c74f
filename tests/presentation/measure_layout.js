// Measures a rendered REI page in the browser and writes the findings as JSON into
// <pre id="layout-report"> (read back from Chromium's --dump-dom). Used by
// tests/report/test_layout.py; nothing here changes the page.
(function () {
  // Measure what a reader can open: every collapsed section is opened first.
  document.querySelectorAll("details").forEach(function (d) { d.open = true; });
  function rgba(text) {
    var m = text.match(/rgba?\(([^)]+)\)/);
    if (!m) { return [0, 0, 0, 0]; }
    var p = m[1].split(",").map(function (x) { return parseFloat(x); });
    return [p[0], p[1], p[2], p.length > 3 ? p[3] : 1];
  }
  function over(top, bottom) {  // alpha-composite top over an opaque bottom
    var a = top[3];
    return [top[0] * a + bottom[0] * (1 - a), top[1] * a + bottom[1] * (1 - a),
            top[2] * a + bottom[2] * (1 - a), 1];
  }
  function luminance(c) {
    var v = c.slice(0, 3).map(function (x) {
      x = x / 255; return x <= 0.03928 ? x / 12.92 : Math.pow((x + 0.055) / 1.055, 2.4); });
    return 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2];
  }
  function contrast(a, b) {
    var la = luminance(a), lb = luminance(b);
    return (Math.max(la, lb) + 0.05) / (Math.min(la, lb) + 0.05);
  }
  function background(el) {  // the opaque colour behind an element (layers composited)
    var layers = [];
    for (var e = el; e && e.nodeType === 1; e = e.parentElement) {
      var c = rgba(getComputedStyle(e).backgroundColor);
      if (c[3] > 0) { layers.push(c); if (c[3] >= 1) { break; } }
    }
    var colour = [255, 255, 255, 1];
    for (var i = layers.length - 1; i >= 0; i--) { colour = over(layers[i], colour); }
    return colour;
  }
  function opacity(el) {
    var o = 1;
    for (var e = el; e && e.nodeType === 1; e = e.parentElement) {
      o *= parseFloat(getComputedStyle(e).opacity);
    }
    return o;
  }
  function describe(el, text) {
    return (el.id ? "#" + el.id : el.tagName.toLowerCase()) + ": " + text.trim().slice(0, 40);
  }
  var report = {width: window.innerWidth, headers: 0, overflowing: [], brokenWords: [],
                lowContrast: [], smallText: [], svgTexts: 0, smallChartText: [],
                shrunkImages: [], minChartPx: 1e9, minContrast: 1e9};
  document.querySelectorAll("th").forEach(function (th) {
    report.headers++;
    var vertical = getComputedStyle(th).writingMode.indexOf("vertical") === 0;
    if (vertical ? th.scrollHeight > th.clientHeight + 1 : th.scrollWidth > th.clientWidth + 1) {
      report.overflowing.push(describe(th, th.textContent));
    }
    var walker = document.createTreeWalker(th, NodeFilter.SHOW_TEXT);
    for (var node = walker.nextNode(); node; node = walker.nextNode()) {
      var re = /[A-Za-z0-9]+/g, m;
      while ((m = re.exec(node.data)) !== null) {
        var range = document.createRange();
        range.setStart(node, m.index);
        range.setEnd(node, m.index + m[0].length);
        var lines = {};
        Array.prototype.forEach.call(range.getClientRects(), function (r) {
          if (r.width > 0 && r.height > 0) { lines[Math.round(vertical ? r.left : r.top)] = 1; }
        });
        if (Object.keys(lines).length > 1) { report.brokenWords.push(m[0] + " in " + th.textContent); }
      }
    }
  });
  // Every element with text of its own: contrast against what is behind it, and size.
  document.querySelectorAll("body *").forEach(function (el) {
    if (el.closest("svg") || el.id === "layout-report" || /^(SCRIPT|STYLE)$/.test(el.tagName)) {
      return;
    }
    var own = Array.prototype.filter.call(el.childNodes, function (n) {
      return n.nodeType === 3 && n.data.trim(); }).map(function (n) { return n.data; }).join(" ");
    if (!own) { return; }
    var box = el.getBoundingClientRect();
    if (box.width === 0 || box.height === 0) { return; }  // collapsed <details> and the like
    var style = getComputedStyle(el);
    var size = parseFloat(style.fontSize);
    var bold = parseInt(style.fontWeight, 10) >= 700;
    var back = background(el);
    var fore = rgba(style.color);
    fore = over([fore[0], fore[1], fore[2], fore[3] * opacity(el)], back);
    var ratio = contrast(fore, back);
    report.minContrast = Math.min(report.minContrast, ratio);
    var needed = (size >= 24 || (size >= 18.66 && bold)) ? 3 : 4.5;
    if (ratio < needed) {
      report.lowContrast.push(describe(el, own) + " (" + ratio.toFixed(2) + ":1)");
    }
    if (size < 11) { report.smallText.push(describe(el, own) + " (" + size + " px)"); }
  });
  // Chart text: its size on screen (the SVG's scale included) and its contrast on white.
  document.querySelectorAll("svg text").forEach(function (t) {
    if (!t.textContent.trim()) { return; }
    report.svgTexts++;
    var m = t.getScreenCTM();
    var px = parseFloat(getComputedStyle(t).fontSize) * Math.hypot(m.a, m.b);
    report.minChartPx = Math.min(report.minChartPx, px);
    if (px < 11) { report.smallChartText.push(t.textContent.trim().slice(0, 30) + " (" + px.toFixed(1) + " px)"); }
    var fill = rgba(getComputedStyle(t).fill);
    var ratio = contrast(over([fill[0], fill[1], fill[2], fill[3] * opacity(t)], [255, 255, 255, 1]),
                         [255, 255, 255, 1]);
    report.minContrast = Math.min(report.minContrast, ratio);
    if (ratio < (px >= 24 ? 3 : 4.5)) {
      report.lowContrast.push("svg text " + t.textContent.trim().slice(0, 30) + " (" + ratio.toFixed(2) + ":1)");
    }
  });
  // Raster maps (text drawn at 12 px in the image) must not be shown smaller than 11/12.
  document.querySelectorAll("img").forEach(function (img) {
    if (img.naturalWidth && img.getBoundingClientRect().width > 0 &&
        img.getBoundingClientRect().width < img.naturalWidth * 11 / 12) {
      report.shrunkImages.push(img.alt + " (" + Math.round(img.getBoundingClientRect().width) +
                               " of " + img.naturalWidth + " px)");
    }
  });
  // The distinct failures lead the page and fit its width (issue 25.4).
  var clusters = document.getElementById("failure-clusters");
  var first = document.querySelector("h2");
  report.firstSection = first ? first.id : "";
  report.clusterRows = clusters ? clusters.tBodies[0].rows.length : 0;
  report.clustersOverflow = clusters ?
    Math.max(0, Math.round(clusters.getBoundingClientRect().right -
                           document.documentElement.clientWidth)) : 0;
  var pre = document.createElement("pre");
  pre.id = "layout-report";
  pre.textContent = JSON.stringify(report);
  document.body.appendChild(pre);
})();
