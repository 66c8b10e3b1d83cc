/* The pages that do the work (upload → review → catalogue; design → predict → lobes), built on
 * the JSON API only: every call goes to /api/v1 with the browser session; a write carries the
 * session's CSRF token (meta name="csrf") in X-CSRF-Token. No inline code (CSP). */
(function () {
  "use strict";

  var SUP = {"-": "⁻", "0": "⁰", "1": "¹", "2": "²", "3": "³", "4": "⁴", "5": "⁵", "6": "⁶", "7": "⁷", "8": "⁸", "9": "⁹"};
  var COLOURS = ["#1f5fa8", "#c0392b", "#2e8b57", "#8e44ad", "#d4780f"];
  var NAMES = {torque_nm: "torque", preload_n: "drawbar force / preload", materials: "materials",
               "geometry.shank_diameter_m": "shank diameter", "geometry.taper_diameter_m": "taper diameter",
               "geometry.insertion_m": "insertion depth"};

  function $(id) { return document.getElementById(id); }

  function eng(v, digits) {  // as the server's web_format.num: 8000 → "8000", 1.45e8 → "1.45 × 10⁸"
    digits = digits || 4;
    if (v === null || v === undefined || !isFinite(v)) return "–";
    if (v === 0) return "0";
    var e = Math.floor(Math.log10(Math.abs(v)));
    if (e >= -3 && e < 6) return String(Number(v.toPrecision(digits)));
    var m = Number((v / Math.pow(10, e)).toPrecision(Math.max(1, digits - 1)));
    return m + " × 10" + String(e).split("").map(function (c) { return SUP[c]; }).join("");
  }

  function api(method, path, body) {
    var meta = document.querySelector("meta[name=csrf]");
    var headers = {"Accept": "application/json"};
    if (method !== "GET") headers["X-CSRF-Token"] = meta ? meta.content : "";
    var init = {method: method, headers: headers, credentials: "same-origin"};
    if (body instanceof FormData) init.body = body;
    else if (body !== undefined) { headers["Content-Type"] = "application/json"; init.body = JSON.stringify(body); }
    return fetch(path, init).then(function (r) {
      return r.json().catch(function () { return {}; }).then(function (j) {
        if (!r.ok) throw new Error(j.error || ("the server answered " + r.status));
        return j;
      });
    });
  }

  function fail(id) {
    return function (err) { var p = $(id); p.textContent = err.message; p.hidden = false; };
  }

  function poll(id, onUpdate) {  // resolves with the job once it is succeeded / failed / cancelled
    return new Promise(function (resolve, reject) {
      function step() {
        api("GET", "/api/v1/jobs/" + encodeURIComponent(id)).then(function (job) {
          onUpdate(job);
          if (["succeeded", "failed", "cancelled"].indexOf(job.state) >= 0) resolve(job);
          else setTimeout(step, 400);
        }, reject);
      }
      step();
    });
  }

  function progress(prefix) {
    return function (job) {
      $(prefix + "-state").textContent = job.state;
      $(prefix + "-message").textContent = job.error || job.message || "";
      $(prefix + "-progress").value = job.state === "succeeded" ? 1 : job.progress;
    };
  }

  function el(tag, text, attrs) {
    var e = document.createElement(tag);
    if (text !== undefined && text !== null) e.textContent = text;
    Object.keys(attrs || {}).forEach(function (k) { e.setAttribute(k, attrs[k]); });
    return e;
  }

  function table(t, header, rows) {
    t.textContent = "";
    var tr = el("tr");
    header.forEach(function (h) { tr.append(el("th", h)); });
    t.append(tr);
    rows.forEach(function (cells) {
      var r = el("tr");
      cells.forEach(function (c) { r.append(c instanceof Node ? (function () { var d = el("td"); d.append(c); return d; })() : el("td", c)); });
      t.append(r);
    });
    return t;
  }

  function plot(holder, spec) {
    var div = el("div", null, {id: "plot-" + spec.id});
    holder.append(div);
    return window.jointdbPlots.draw(spec, div);
  }

  function blobLink(a, text, mime) { a.href = URL.createObjectURL(new Blob([text], {type: mime})); }

  function pngLink(a, holder) {  // the first plot's canvas (uPlot draws axes and curves on it)
    a.addEventListener("click", function () {
      var c = holder.querySelector("canvas");
      if (c) a.href = c.toDataURL("image/png");
    });
  }

  function num(id, what, factor) {
    var t = ($(id).value || "").trim();
    if (t === "") return null;
    var v = Number(t.replace(",", "."));
    if (!isFinite(v)) throw new Error(what + ": " + t + " is not a number");
    return v * (factor || 1);
  }

  function conditionsFrom(prefix) {  // the condition fields of a form, in SI
    var c = {};
    var mats = ($(prefix + "-materials").value || "").split("+").map(function (m) { return m.trim(); })
      .filter(function (m) { return m; });
    if (mats.length) c.materials = mats;
    var t = num(prefix + "-torque", "clamping torque [N·m]"), f = num(prefix + "-force", "drawbar force [kN]", 1000);
    if (t !== null) c.torque_nm = t;
    if (f !== null) c.preload_n = f;
    return c;
  }

  function units(dof) {  // k and c units of a joint DOF label ("3x", "3ry")
    return /^\d*r/.test(String(dof)) ? ["N·m/rad", "N·m·s/rad"] : ["N/m", "N·s/m"];
  }

  function perCondition(per) {
    return Object.keys(per || {}).map(function (k) { return (NAMES[k] || k) + " " + eng(per[k], 3); }).join(", ");
  }

  /* ---------------------------------------------------------------- upload */
  var CRC = (function () {
    var t = [];
    for (var n = 0; n < 256; n++) {
      var c = n;
      for (var k = 0; k < 8; k++) c = c & 1 ? 0xEDB88320 ^ (c >>> 1) : c >>> 1;
      t.push(c >>> 0);
    }
    return t;
  })();

  function crc32(bytes) {
    var c = 0xFFFFFFFF;
    for (var i = 0; i < bytes.length; i++) c = CRC[(c ^ bytes[i]) & 0xFF] ^ (c >>> 8);
    return (c ^ 0xFFFFFFFF) >>> 0;
  }

  function zip(entries) {  // [{name, bytes}] -> a stored (uncompressed) .zip as a Blob
    var parts = [], central = [], offset = 0, enc = new TextEncoder();
    function head(size) { var b = new DataView(new ArrayBuffer(size)); return b; }
    entries.forEach(function (e) {
      var name = enc.encode(e.name), crc = crc32(e.bytes), n = e.bytes.length;
      var l = head(30);
      [[0, 0x04034b50, 4], [4, 20, 2], [6, 0x0800, 2], [8, 0, 2], [10, 0, 2], [12, 0x21, 2], [14, crc, 4],
       [18, n, 4], [22, n, 4], [26, name.length, 2], [28, 0, 2]].forEach(function (f) {
        if (f[2] === 4) l.setUint32(f[0], f[1], true); else l.setUint16(f[0], f[1], true);
      });
      var c = head(46);
      [[0, 0x02014b50, 4], [4, 20, 2], [6, 20, 2], [8, 0x0800, 2], [10, 0, 2], [12, 0, 2], [14, 0x21, 2], [16, crc, 4],
       [20, n, 4], [24, n, 4], [28, name.length, 2], [30, 0, 2], [32, 0, 2], [34, 0, 2], [36, 0, 2], [38, 0, 4],
       [42, offset, 4]].forEach(function (f) {
        if (f[2] === 4) c.setUint32(f[0], f[1], true); else c.setUint16(f[0], f[1], true);
      });
      parts.push(l, name, e.bytes);
      central.push(c, name);
      offset += 30 + name.length + n;
    });
    var size = central.reduce(function (s, x) { return s + x.byteLength; }, 0), end = head(22);
    [[0, 0x06054b50, 4], [8, entries.length, 2], [10, entries.length, 2], [12, size, 4], [16, offset, 4]]
      .forEach(function (f) { if (f[2] === 4) end.setUint32(f[0], f[1], true); else end.setUint16(f[0], f[1], true); });
    return new Blob(parts.concat(central, [end]), {type: "application/zip"});
  }

  function flatten(value, names) {  // a campaign's file paths -> the uploaded files' own names
    if (typeof value === "string") {
      var base = value.split(/[\\/]/).pop();
      return (value !== base && names.indexOf(base) >= 0) ? base : value;
    }
    if (Array.isArray(value)) return value.map(function (v) { return flatten(v, names); });
    if (value && typeof value === "object") {
      var out = {};
      Object.keys(value).forEach(function (k) { out[k] = flatten(value[k], names); });
      return out;
    }
    return value;
  }

  function archiveOf(files) {  // individual files (a campaign file among them) -> a campaign archive
    var names = files.map(function (f) { return f.name; });
    return Promise.all(files.map(function (f) { return f.arrayBuffer(); })).then(function (buffers) {
      var found = false;
      var entries = files.map(function (f, i) {
        var bytes = new Uint8Array(buffers[i]);
        if (/\.json$/i.test(f.name)) {
          try {
            var doc = JSON.parse(new TextDecoder().decode(bytes));
            if (doc && doc.format === "jointdb-campaign/1") {
              found = true;
              bytes = new TextEncoder().encode(JSON.stringify(flatten(doc, names), null, 1));
            }
          } catch (err) { /* not JSON: a model file is checked by the server */ }
        }
        return {name: f.name, bytes: bytes};
      });
      if (!found) {
        throw new Error("none of the files is a campaign file (format jointdb-campaign/1): add it, or write one "
                        + "with `jointdb campaign init` on the folder");
      }
      return zip(entries);
    });
  }

  function upload() {
    $("upload-form").addEventListener("submit", function (ev) {
      ev.preventDefault();
      $("u-error").hidden = true;
      var file = $("u-file").files[0], files = Array.prototype.slice.call($("u-files").files);
      var fd = new FormData(), ready;
      try {
        if (!file && !files.length) throw new Error("choose a campaign archive (.zip) or the campaign's files");
        ready = file ? Promise.resolve(file) : archiveOf(files);
        if ($("u-name").value.trim()) fd.append("name", $("u-name").value.trim());
        fd.append("conditions", JSON.stringify(conditionsFrom("u")));
      } catch (err) { fail("u-error")(err); return; }
      $("u-submit").disabled = true;
      ready.then(function (blob) {
        fd.append("file", blob, file ? file.name : "campaign.zip");
        return api("POST", "/api/v1/jobs/identify", fd);
      }).then(function (job) {
        window.location.assign("/ui/jobs/" + encodeURIComponent(job.id));
      }, function (err) { $("u-submit").disabled = false; fail("u-error")(err); });
    });
  }

  /* ---------------------------------------------------------------- jobs */
  function jobs() {
    api("GET", "/api/v1/jobs").then(function (j) {
      table($("jobs"), ["job", "kind", "state", "progress", "message", "submitted (UTC)"], j.items.map(function (x) {
        var a = el("a", x.id.slice(0, 12), {href: "/ui/jobs/" + x.id});
        return [a, x.kind, x.state, Math.round(100 * x.progress) + " %", x.error || x.message || "",
                (x.created || "").replace("T", " ").slice(0, 19)];
      }));
    }, fail("jobs-error"));
  }

  function job() {
    var id = $("job").dataset.job;
    $("job-cancel").addEventListener("click", function () {
      api("POST", "/api/v1/jobs/" + id + "/cancel").catch(fail("job-error"));
    });
    poll(id, function (j) {
      progress("job")(j);
      $("job-kind").textContent = j.kind + " job";
      $("job-cancel").hidden = ["queued", "running"].indexOf(j.state) < 0;
    }).then(function (j) {
      if (j.state === "failed") fail("job-error")(new Error(j.error || "the job failed"));
      if (j.state !== "succeeded") return;
      if (j.kind === "identify" && !j.outcome) review(j);
      else if (j.outcome) done(j.outcome);
      else { $("result").hidden = false; $("result-json").textContent = JSON.stringify(j.result, null, 1); }
    }, fail("job-error"));
  }

  function done(outcome) {
    var p = $("done-text");
    p.textContent = "";
    if (outcome.action === "catalogued") {
      p.append("catalogued as ", el("a", outcome.name + " v" + outcome.version,
               {href: "/ui/joints/" + encodeURIComponent(outcome.name) + "?version=" + outcome.version, id: "done-link"}));
    } else p.textContent = "discarded: nothing was catalogued";
    $("done").hidden = false;
    $("review").hidden = true;
  }

  function review(j) {
    var r = j.result;
    $("review").hidden = false;
    table($("review-kc"), ["DOF", "k", "± σ", "c", "± σ", "fit error"], r.parameters.map(function (p) {
      var s = function (v, u) { return v === null || v === undefined ? "(σ not estimated)" : "± " + eng(v, 2) + " " + u; };
      var u = units(p.dof);
      return [p.dof, eng(p.k) + " " + u[0], s(p.k_sigma, u[0]), eng(p.c) + " " + u[1],
              s(p.c_sigma, u[1]), p.fit_error === null || p.fit_error === undefined ? "–" : eng(100 * p.fit_error, 2) + " %"];
    }));
    var v = $("review-verdict"), lines = r.verdict || [];
    v.textContent = "";
    v.append(el("strong", "Quality verdict:"));
    lines.forEach(function (line) { v.append(el("p", line.replace(/^verdict:\s*/, ""))); });
    if (!lines.length) v.append(el("p", "no verdict in the identification report"));
    v.className = "verdict " + (lines.length && /^(verdict:\s*)?OK/.test(lines[0]) && lines.length === 1 ? "ok" : "warn");
    var box = $("review-contradictions");
    box.textContent = "";
    (r.contradictions || []).forEach(function (c) {  // the use case's words are the CLI's: say them as the page's
      c = c.replace(/--(torque|preload|material|geometry|extra) gives/g, "the upload form gives")
        .replace(/leave the option out to keep the file's value, or add --force to store the option's value/,
                 "keep the campaign's value below, or tick \u201cstore my values\u201d to store yours")
        .replace(/torque_nm/g, "torque [N·m]").replace(/preload_n/g, "drawbar force / preload [N]");
      box.append(el("p", "Contradiction: " + c, {"class": "error contradiction"}));
    });
    var c = r.conditions || {};
    $("c-name").value = r.suggested_name || r.campaign || "";
    $("c-materials").value = (c.materials || []).join(" + ");
    $("c-torque").value = c.torque_nm === null || c.torque_nm === undefined ? "" : c.torque_nm;
    $("c-force").value = c.preload_n === null || c.preload_n === undefined ? "" : c.preload_n / 1000;
    var geo = $("c-geometry");
    Object.keys(c.geometry || {}).forEach(function (k) {
      var label = el("label", (NAMES["geometry." + k] || k.replace(/_m$/, "").replace(/_/g, " ")) + " [mm] ");
      label.append(el("input", null, {id: "c-geo-" + k, "data-key": k, size: "6", value: String(Number((c.geometry[k] * 1000).toPrecision(6)))}));
      geo.append(label);
    });
    reviewPlots(r.curves || {});
    $("catalogue-form").addEventListener("submit", function (ev) {
      ev.preventDefault();
      var body;
      try {
        var cond = conditionsFrom("c");
        cond.geometry = {};
        geo.querySelectorAll("input").forEach(function (i) { cond.geometry[i.dataset.key] = num(i.id, i.dataset.key, 1e-3); });
        body = {name: $("c-name").value.trim(), conditions: cond, force: $("c-force-flag").checked};
        if ($("c-label").value.trim()) body.label = $("c-label").value.trim();
      } catch (err) { fail("job-error")(err); return; }
      api("POST", "/api/v1/jobs/" + j.id + "/catalogue", body).then(function (v) {
        done({action: "catalogued", name: v.name, version: v.version});
      }, fail("job-error"));
    });
    $("discard").addEventListener("click", function () {
      api("POST", "/api/v1/jobs/" + j.id + "/discard").then(function () { done({action: "discarded"}); }, fail("job-error"));
    });
  }

  function reviewPlots(curves) {
    var holder = $("review-plots"), a = curves.assembly || {}, jt = curves.joint || {};
    (a.entries || []).forEach(function (e, i) {
      var series = [{label: "measured [" + e.unit + "]", y: e.measured, colour: COLOURS[0], dash: []},
                    {label: "re-coupled with the joint [" + e.unit + "]", y: e.recoupled, colour: COLOURS[1], dash: [8, 4]}];
      if (e.rigid) series.push({label: "rigid joint [" + e.unit + "]", y: e.rigid, colour: COLOURS[2], dash: [2, 3]});
      series.forEach(function (s) { s.x = a.freq_hz; });
      plot(holder, {id: "assembly-" + i, title: "assembly " + e.entry, x: "frequency [Hz]", y: "|H| [" + e.unit + "]",
                    log: true, series: series});
    });
    ["k", "c"].forEach(function (what) {
      var byUnit = {};
      (jt.dofs || []).forEach(function (d) {
        var u = units(d.dof)[what === "k" ? 0 : 1];
        (byUnit[u] = byUnit[u] || []).push(d);
      });
      Object.keys(byUnit).forEach(function (unit, n) {
        plot(holder, {id: what + "-" + n, title: what + "(ω) of the joint", x: "frequency [Hz]", y: what + " [" + unit + "]",
                      log: false, series: byUnit[unit].map(function (d, i) {
                        return {label: what + " " + d.dof + " [" + unit + "]", x: jt.freq_hz, y: d[what], colour: COLOURS[i], dash: []};
                      })});
      });
    });
  }

  window.jointdbFlow = {api: api, poll: poll, eng: eng, table: table, plot: plot, el: el, fail: fail, num: num,
                        progress: progress, blobLink: blobLink, pngLink: pngLink, perCondition: perCondition,
                        COLOURS: COLOURS};
  var page = document.querySelector("[data-page]");
  var run = {upload: upload, jobs: jobs, job: job}[page ? page.dataset.page : ""];
  function start() { if (run) run(); }
  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start); else start();
})();
