/* Design a stack from the parts library, find the nearest joints, predict the tool tip as a job,
 * then draw stability lobes as a job — on the JSON API only (helpers: flow.js). */
(function () {
  "use strict";
  var F = window.jointdbFlow, $ = function (id) { return document.getElementById(id); };
  var lib = JSON.parse($("library").textContent);
  var parts = {}, state = {};

  function option(select, value, text) {
    var o = document.createElement("option");
    o.value = value;
    o.textContent = text;
    select.append(o);
  }

  function loadParts(kind, select) {
    return F.api("GET", "/api/v1/parts?kind=" + kind + "&limit=500").then(function (j) {
      select.textContent = "";
      if (!j.items.length) option(select, "", "no " + kind + " catalogued yet");
      j.items.forEach(function (p) {
        var a = p.attributes || {}, g = p.geometry || {};
        var what = [a.machine, a.family, a.taper, g.length_mm ? F.eng(g.length_mm, 3) + " mm long" : null,
                    g.bore_mm || a.bore_mm ? "bore " + F.eng(g.bore_mm || a.bore_mm, 3) + " mm" : null,
                    g.source === "measured" ? "measured FRF" : null]
          .filter(function (x) { return x; }).join(", ");
        parts[p.name + "@" + p.version] = p;
        option(select, p.name + "@" + p.version, p.name + " v" + p.version + (what ? " — " + what : ""));
      });
    });
  }

  function part(ref) {  // one part version's record and payload (verified on read by the server)
    var i = ref.lastIndexOf("@");
    return F.api("GET", "/api/v1/parts/" + encodeURIComponent(ref.slice(0, i)) + "/" + encodeURIComponent(ref.slice(i + 1)));
  }

  function catalogueMaterial(m) {
    var hit = lib.tool_materials.filter(function (t) { return t.stack === m; })[0];
    return hit ? hit.catalogue : (m === "carbide" ? "tungsten-carbide" : m);
  }

  function queries(holder) {  // the two interfaces' nearest-joint queries, in SI
    var d = F.num("d-diameter", "tool diameter [mm]", 1e-3), taper = (parts[$("d-holder").value].attributes || {}).taper;
    var hmat = catalogueMaterial((holder && holder.payload && holder.payload.material) || "steel");
    var th = {joint_type: "tool-holder", materials: [catalogueMaterial($("d-material").value), hmat],
              torque_nm: F.num("d-torque", "clamping torque [N·m]"), geometry: {shank_diameter_m: d}};
    var hs = {joint_type: "holder-spindle", materials: [hmat, "steel"], preload_n: F.num("d-force", "drawbar force [kN]", 1000),
              geometry: {}};
    if (taper && lib.tapers[taper]) hs.geometry.taper_diameter_m = lib.tapers[taper];
    return {"tool-holder": th, "holder-spindle": hs};
  }

  function nearestTable(target, q, interpolate) {
    var body = {joint_type: q.joint_type, k: 3, conditions: {materials: q.materials, torque_nm: q.torque_nm,
                preload_n: q.preload_n, geometry: q.geometry}};
    var calls = [F.api("POST", "/api/v1/query/nearest", body)];
    if (interpolate) calls.push(F.api("POST", "/api/v1/query/interpolate", body));
    return Promise.all(calls).then(function (res) {
      var weights = {};
      if (res[1]) res[1].neighbours.forEach(function (n) { weights[n.name + "@" + n.version] = n.weight; });
      var t = document.createElement("table");
      t.className = "wide nearest";
      F.table(t, ["rank", "joint", "distance", interpolate ? "weight" : "used", "per condition"], res[0].matches.map(function (m, i) {
        var a = F.el("a", m.name + " v" + m.version, {href: "/ui/joints/" + encodeURIComponent(m.name) + "?version=" + m.version});
        var w = weights[m.name + "@" + m.version];
        return [String(i + 1), a, F.eng(m.distance, 3), interpolate ? (w === undefined ? "0" : F.eng(w, 3)) : (i === 0 ? "yes" : ""),
                F.perCondition(m.per_condition) + (m.extrapolating ? " (extrapolating)" : "")];
      }));
      target.textContent = "";
      target.append(t);
      (res[0].warnings || []).concat(res[1] ? res[1].warnings : []).forEach(function (w) {
        target.append(F.el("p", w.replace(/preload_n/g, "drawbar force").replace(/torque_nm/g, "torque")
          .replace(/geometry\.(\w+)_m/g, function (_, k) { return k.replace(/_/g, " "); }), {"class": "note"}));
      });
    });
  }

  function nearest() {
    $("d-error").hidden = true;
    return part($("d-holder").value).then(function (holder) {
      var q = queries(holder), interp = $("d-interpolate").checked;
      $("nearest").hidden = false;
      return Promise.all([nearestTable($("nearest-th"), q["tool-holder"], interp),
                          nearestTable($("nearest-hs"), q["holder-spindle"], interp)]);
    }).catch(F.fail("d-error"));
  }

  function stack(holder, spindle) {
    var d = F.num("d-diameter", "tool diameter [mm]", 1e-3), flute = F.num("d-flute", "flute length [mm]", 1e-3);
    var total = F.num("d-length", "total length [mm]", 1e-3), gauge = F.num("d-overhang", "overhang [mm]", 1e-3);
    if (!(total > flute && flute > 0)) throw new Error("the total length must exceed the flute length");
    if (spindle.payload.model === undefined) {
      throw new Error("spindle " + spindle.name + " is a measured FRF set: a predict job takes a modelled spindle "
                      + "inline only (its submission does not yet accept part references)");
    }
    var q = queries(holder), interp = $("d-interpolate").checked;
    ["tool-holder", "holder-spindle"].forEach(function (k) { q[k].interpolate = interp; q[k].neighbours = 3; });
    return {format: "jointdb-stack/1", name: "designed on the web page", gauge_length: gauge,
            frequency: {min: 50.0, max: 4990.0, step: 10.0},  // within the bundled joints' 50–4990 Hz
            tool: {material: $("d-material").value, segments: [{diameter: d, length: flute, fluted: true},
                                                               {diameter: d, length: total - flute}]},
            holder: holder.payload, spindle: spindle.payload,
            interfaces: {"tool-holder": {query: q["tool-holder"]}, "holder-spindle": {query: q["holder-spindle"]}}};
  }

  function predict() {
    $("d-error").hidden = true;
    var used;
    nearest();  // the candidates shown are those of the stack being predicted
    Promise.all([part($("d-holder").value), part($("d-spindle").value)]).then(function (hs) {
      used = hs;
      return F.api("POST", "/api/v1/jobs/predict", {stack: stack(hs[0], hs[1])});
    }).then(function (job) {
      $("prediction").hidden = false;
      $("p-result").hidden = true;
      $("p-job").textContent = job.id.slice(0, 12);
      $("p-job").href = "/ui/jobs/" + job.id;
      return F.poll(job.id, F.progress("p"));
    }).then(function (job) {
      if (job.state !== "succeeded") throw new Error(job.error || "the prediction job " + job.state);
      showPrediction(job.result, used);
    }).catch(F.fail("d-error"));
  }

  function entries(frf) {  // the diagonal entries of an FRF JSON: [{label, mag, phase}]
    var out = [];
    frf.outputs.forEach(function (o, i) {
      var j = frf.inputs.indexOf(o);
      if (j < 0) return;
      var mag = [], ph = [];
      frf.real.forEach(function (re, f) {
        var a = re[i][j], b = frf.imag[f][i][j];
        mag.push(Math.hypot(a, b));
        ph.push(Math.atan2(b, a) * 180 / Math.PI);
      });
      out.push({label: o, mag: mag, phase: ph});
    });
    return out;
  }

  function showPrediction(r, used) {
    state.prediction = r;
    $("p-result").hidden = false;
    F.table($("p-summary"), ["plane", "peak [Hz]", "peak |H| [m/N]", "rigid joints: peak [Hz]", "rigid: |H| [m/N]"],
            r.prediction.map(function (p) {
              return [p.direction, F.eng(p.peak_hz), F.eng(p.peak_m_per_n, 3), F.eng(p.rigid_peak_hz), F.eng(p.rigid_peak_m_per_n, 3)];
            }));
    F.table($("p-joints"), ["interface", "joint", "distance", "how"], r.joints.map(function (j) {
      return [j.interface, j.joint || "", j.distance === null ? "–" : F.eng(j.distance, 3), j.kind + (j.extrapolating ? " (extrapolating)" : "")];
    }));
    F.table($("p-parts"), ["part", "version", "kind"], used.map(function (p) { return [p.name, "v" + p.version, p.kind]; }));
    (r.joint_choice_sensitivity || []).forEach(function (x) {  // what the next-nearest joint would change
      $("p-joints").append(F.el("tr")); var tr = $("p-joints").lastChild;
      [x.interface, "next: " + x.alternative, F.eng(x.distance, 3), "peak " + x.direction + " " +
       (x.peak_change >= 0 ? "+" : "") + F.eng(100 * x.peak_change, 2) + " %"].forEach(function (t) { tr.append(F.el("td", t)); });
    });
    var notes = (r.notes || []).concat(r.band ? [] : ["no band: none of the chosen joints carries a parameter covariance"]);
    $("p-notes").textContent = notes.join(" · ");
    $("p-notes").hidden = !notes.length;
    var holder = $("p-plots"), tip = entries(r.tip_frf), rigid = entries(r.rigid_tip_frf), f = r.tip_frf.freq_hz;
    holder.textContent = "";
    var mag = [], phase = [];
    [[tip, "with the joints", F.COLOURS[0]], [rigid, "rigid joints", F.COLOURS[1]]].forEach(function (set) {
      set[0].forEach(function (e, i) {
        var dash = i === 0 ? [] : [8, 4];
        mag.push({label: "tip " + e.label + "/" + e.label + " " + set[1] + " [m/N]", x: f, y: e.mag, colour: set[2], dash: dash});
        phase.push({label: "tip " + e.label + " " + set[1] + " [deg]", x: f, y: e.phase, colour: set[2], dash: dash});
      });
    });
    if (r.band) {  // the 5–95 % band from the chosen joints' parameter covariance
      Object.keys(r.band.magnitude_m_per_n).forEach(function (d, i) {
        var m = r.band.magnitude_m_per_n[d];
        [["p05", "5 %"], ["p95", "95 %"]].forEach(function (q) {
          mag.push({label: "tip " + d + " band " + q[1] + " [m/N]", x: r.band.frequency_hz, y: m[q[0]], colour: "#8a99aa",
                    dash: i === 0 ? [2, 2] : [6, 2, 2, 2]});
        });
      });
      F.table($("p-band"), ["plane", "peak |H| 5 % [m/N]", "median", "95 %", "peak frequency 5–95 % [Hz]"],
              r.band.peaks.map(function (b) {
                return [b.direction, F.eng(b.peak_m_per_n_p05, 4), F.eng(b.peak_m_per_n_p50, 4), F.eng(b.peak_m_per_n_p95, 4),
                        F.eng(b.peak_hz_p05) + "–" + F.eng(b.peak_hz_p95)];
              }));
      $("p-band-text").textContent = "5–95 % band from " + r.band.samples + " joints sampled from the parameter "
        + "covariance of " + r.band.interfaces.join(", ") + ":";
    }
    $("p-band-box").hidden = !r.band;
    F.plot(holder, {id: "tip-mag", title: "tool tip, x plane solid, y plane dashed" + (r.band ? "; grey: 5–95 % band" : ""),
                    x: "frequency [Hz]", y: "|H| [m/N]", log: true, series: mag});
    F.plot(holder, {id: "tip-phase", title: "tool tip: phase", x: "frequency [Hz]", y: "phase [deg]", log: false, series: phase});
    var csv = ["freq_hz," + tip.map(function (e) { return "abs_" + e.label + "_m_per_n,phase_" + e.label + "_deg"; })
      .concat(rigid.map(function (e) { return "rigid_abs_" + e.label + "_m_per_n"; })).join(",")];
    f.forEach(function (x, k) {
      csv.push([x].concat(tip.reduce(function (a, e) { return a.concat([e.mag[k], e.phase[k]]); }, []),
                          rigid.map(function (e) { return e.mag[k]; })).join(","));
    });
    F.blobLink($("p-csv"), csv.join("\n") + "\n", "text/csv");
    F.blobLink($("p-json"), JSON.stringify(r, null, 1), "application/json");
    F.pngLink($("p-png"), holder);
    $("lobes").hidden = false;
    $("l-teeth").value = $("d-flutes").value;
  }

  function pickMaterial() {
    var m = lib.materials[$("l-material").selectedIndex];
    $("l-unit").value = "nmm2";
    $("l-kt").value = m.kt;
    $("l-kr").value = m.kr;
    $("l-source").textContent = "source: " + m.source;
  }

  function lobes() {
    $("d-error").hidden = true;
    var body, notes = [];
    try {
      var factor = $("l-unit").value === "nmm2" ? 1e6 : 1;
      var kt = F.num("l-kt", "Kt"), kr = F.num("l-kr", "Kr");
      if (factor !== 1) notes.push("Kt " + F.eng(kt) + " N/mm² = " + F.eng(kt * 1e6) + " N/m², Kr " + F.eng(kr) +
                                   " N/mm² = " + F.eng(kr * 1e6) + " N/m² (converted here)");
      body = {frf: state.prediction.tip_frf, op: "milling", method: $("l-method").value, teeth: Math.round(F.num("l-teeth", "teeth")),
              kt: kt * factor, kr: kr * factor, immersion: F.num("l-immersion", "immersion"), up: $("l-up").value === "up",
              rpm_min: F.num("l-rpm-min", "lowest speed"), rpm_max: F.num("l-rpm-max", "highest speed"),
              n_speeds: Math.round(F.num("l-n", "speeds"))};
    } catch (err) { F.fail("d-error")(err); return; }
    $("l-result").hidden = true;
    F.api("POST", "/api/v1/jobs/lobes", body).then(function (job) {
      $("l-job").textContent = job.id.slice(0, 12);
      $("l-job").href = "/ui/jobs/" + job.id;
      return F.poll(job.id, F.progress("l"));
    }).then(function (job) {
      if (job.state !== "succeeded") throw new Error(job.error || "the lobes job " + job.state);
      showLobes(job.result, notes);
    }).catch(F.fail("d-error"));
  }

  function showLobes(r, notes) {
    $("l-result").hidden = false;
    var box = $("l-notes");
    box.textContent = "";
    notes.concat(r.notes || []).forEach(function (n) { box.append(F.el("p", n, {"class": "note"})); });
    var s = r.summary || {};
    F.table($("l-summary"), ["what", "value"], [
      ["method", r.method], ["unconditionally stable below", F.eng(1000 * s.min_depth_m, 3) + " mm"],
      ["at", F.eng(s.min_depth_speed_rpm) + " rpm (chatter " + F.eng(s.min_depth_chatter_freq_hz) + " Hz)"],
      ["deepest pocket", F.eng(1000 * s.best_pocket_depth_m, 3) + " mm at " + F.eng(s.best_pocket_speed_rpm) + " rpm"],
      ["speeds computed", String(s.speeds) + " (" + s.speeds_added_by_refinement + " added by refinement)"]]);
    F.table($("l-best"), ["spindle speed [rpm]", "limiting depth [mm]"], (r.best_speeds || []).map(function (b) {
      return [F.eng(b.spindle_speed_rpm), F.eng(1000 * b.depth_m, 3)];
    }));
    var rows = r.rows.slice().sort(function (a, b) { return a.spindle_speed_rpm - b.spindle_speed_rpm; });
    var x = rows.map(function (w) { return w.spindle_speed_rpm; });
    var y = rows.map(function (w) { return w.depth_m === null || w.kind === "fold" ? null : 1000 * w.depth_m; });
    var holder = $("l-plots");
    holder.textContent = "";
    F.plot(holder, {id: "lobes", title: "stability lobes (" + r.method + "): stable below the line (shaded)",
                    x: "spindle speed [rpm]", y: "axial depth of cut [mm]", log: false, ymin: 0,
                    series: [{label: "limiting depth [mm]", x: x, y: y, colour: F.COLOURS[0], dash: [],
                              fill: "rgba(46, 139, 87, 0.18)"}]});
    var csv = ["spindle_speed_rpm,depth_m,chatter_freq_hz,lobe,kind"].concat(rows.map(function (w) {
      return [w.spindle_speed_rpm, w.depth_m === null ? "" : w.depth_m, w.chatter_freq_hz === null ? "" : w.chatter_freq_hz,
              w.lobe, w.kind].join(",");
    }));
    F.blobLink($("l-csv"), csv.join("\n") + "\n", "text/csv");
    F.blobLink($("l-json"), JSON.stringify(r, null, 1), "application/json");
    F.pngLink($("l-png"), holder);
  }

  function start() {
    lib.tool_materials.forEach(function (t) { option($("d-material"), t.stack, t.stack); });
    lib.materials.forEach(function (m) { option($("l-material"), m.name, m.name); });
    $("l-material").addEventListener("change", pickMaterial);
    pickMaterial();
    Promise.all([loadParts("spindle", $("d-spindle")), loadParts("holder", $("d-holder"))]).catch(F.fail("d-error"));
    $("d-nearest").addEventListener("click", nearest);
    $("d-predict").addEventListener("click", predict);
    $("l-run").addEventListener("click", lobes);
  }
  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start); else start();
})();
