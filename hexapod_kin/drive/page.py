"""The cockpit's page: meshcat's scene, a panel per mode, the websocket to the server.

One page (:func:`drive_page`) on :mod:`hexapod_kin._page`: the robot's scene is the viewer's
(:func:`hexapod_kin.viewer.scene_commands`, msgpack, inlined); meshcat's bundle comes from the
same loopback server (no CDN); the page's Content-Security-Policy allows nothing else. Every
tick the server sends the visuals' poses and the readout (:func:`state_frame`). For scripts and
tests the page exposes ``window.hexapodKin`` (``send(msg)``, ``state``, ``fps()``,
``latencies``, ``setContinuous(on)``).
"""

from __future__ import annotations

import base64
import math
from typing import Any

import numpy as np

from .._page import fill, page, script_json
from ..viewer import scene_commands
from ..viewer.objects import pack
from ..viewer.scene import Scene
from .physics import PUSH_WEIGHTS, kind_of
from .reach import SIGMA_EPS
from .state import BODY_ANGLE, BODY_SHIFT, Cockpit

__all__ = ["drive_page", "state_frame", "visual_groups"]

_CSP = (
    "default-src 'none'; script-src 'self' 'unsafe-inline'; style-src 'unsafe-inline'; "
    "img-src data: blob:; connect-src 'self'; worker-src blob:"
)

_STYLE = """body { margin: 0; overflow: hidden; font-family: sans-serif; }
#meshcat-pane { width: 100vw; height: 100vh; overflow: hidden; }
#hk-panel { position: absolute; left: 8px; top: 8px; width: 400px; max-height: 96vh;
  overflow-y: auto; padding: 6px 10px; border-radius: 6px; background: rgba(255,255,255,0.88);
  color: #222; font-size: 12px; line-height: 1.4; }
#hk-panel b { font-size: 14px; }
#hk-panel pre { margin: 2px 0; font-size: 10px; white-space: pre-wrap; }
#hk-panel input[type=range] { width: 170px; vertical-align: middle; }
.hk-tab { display: none; } .hk-tab.on { display: block; }
#hk-modes button.on { font-weight: bold; background: #cde; }
#hk-msg { color: #a00; min-height: 1em; }
#hk-margin.lost, #hk-zmp.lost { color: #d00; font-weight: bold; }
.hk-num { width: 64px; }
#hk-stick { position: relative; width: 90px; height: 90px; border-radius: 45px;
  background: #dde; touch-action: none; margin: 4px 0; }
#hk-knob { position: absolute; left: 30px; top: 30px; width: 30px; height: 30px;
  border-radius: 15px; background: #558; pointer-events: none; }"""

_BODY = """<div id="meshcat-pane"></div>
<div id="hk-panel"><b id="hk-title"></b> <span id="hk-conn">connecting…</span><br>
<span id="hk-modes"></span>
<div class="hk-tab" id="hk-tab-joints"><div id="hk-joints"></div></div>
<div class="hk-tab" id="hk-tab-target">foot/tool <select id="hk-foot"></select><br>
target [m] <input class="hk-num" id="hk-tx"><input class="hk-num" id="hk-ty">
<input class="hk-num" id="hk-tz"> <button id="hk-go">go</button><br>
<span class="hk-help">shift+click in the view: target on the horizontal plane at its height</span>
</div>
<div class="hk-tab" id="hk-tab-body"><div id="hk-body"></div></div>
<div class="hk-tab" id="hk-tab-walk">pattern <select id="hk-pattern"></select>
<span class="hk-help">W/S forward, A/D sideways, Q/E turn (hold)</span><br>
command <span id="hk-cmd"></span><br>actual <span id="hk-act"></span><br>
min margin while walking <span id="hk-minm"></span><br>
<div id="hk-stick"><div id="hk-knob"></div></div>
<span class="hk-help">drag: up/down forward, left/right turn</span></div>
<div class="hk-tab" id="hk-tab-physics">MuJoCo under the closed-loop controller:
W/S, A/D, Q/E (hold) set its velocity; <b>click</b> the scene to push the robot
(<span id="hk-pushn"></span> for 0.1 s, horizontally along the view)<br>
pattern <select id="hk-ppattern"></select> (the controller's; switched at its next cycle)<br>
command <span id="hk-pcmd"></span><br>
actual <span id="hk-pact"></span></div>
<div id="hk-msg"></div>
<pre id="hk-status"></pre>
FK (<code>fk()</code>, base frame):<pre id="hk-fk"></pre>
<div id="hk-legged">margin <span id="hk-margin"></span> · ZMP margin <span id="hk-zmp">-</span>
· CoM <span id="hk-com"></span></div>
<button id="hk-reset">reset</button>
<button id="hk-json">download session (JSON)</button>
<button id="hk-csv">download servo timeline (CSV)</button>
</div>
<script src="/meshcat.js"></script>
<script>
(function () {
  "use strict";
  var DATA = $data;
  var el = function (id) { return document.getElementById(id); };
  function bytes(b64) {
    var s = atob(b64), out = new Uint8Array(s.length);
    for (var i = 0; i < s.length; i++) { out[i] = s.charCodeAt(i); }
    return out;
  }
  // meshcat's renderer without multisampling or shadow maps (their fill costs most of a frame
  // in software GL); the resolution adapts to keep >= 30 frames/s (adapt() below)
  var renderer = new MeshCat.THREE.WebGLRenderer({ antialias: false, alpha: true });
  el("meshcat-pane").appendChild(renderer.domElement);
  var viewer = new MeshCat.Viewer(el("meshcat-pane"), true, renderer);
  DATA.scene.forEach(function (c) { viewer.handle_command_bytearray(bytes(c)); });
  // lighting: the ambient and the directional light only (each light is per-pixel work for
  // every Phong surface in software GL; the spot and point lights cost a third of a frame)
  viewer.scene.traverse(function (o) {
    if (o.isLight && o.type !== "AmbientLight" && o.type !== "DirectionalLight") {
      o.visible = false;
    }
    if (o.isLight && o.type === "DirectionalLight") { o.intensity *= 1.6; }
  });
  viewer.scene.traverse(function (o) {
    var g = o.geometry;
    if (o.isMesh && g && g.isBufferGeometry && g.index && !g.getAttribute("normal")) {
      g.computeVertexNormals();
    }
  });
  var THREE = MeshCat.THREE;
  var split = function (p) { return p.split("/").filter(Boolean); };
  var paths = DATA.groups.map(function (g) { return split(DATA.visuals[g[0]]); });
  function place(node, P, o) {  // a 3×4 [R | p], column-major (12 numbers from o)
    node.set_transform([P[o], P[o + 1], P[o + 2], 0, P[o + 3], P[o + 4], P[o + 5], 0,
                        P[o + 6], P[o + 7], P[o + 8], 0, P[o + 9], P[o + 10], P[o + 11], 1]);
  }
  // per frame, software GL pays per pixel and per draw call: every visual of one group (rigid
  // on one joint) moves with the group's first one and its opaque untextured meshes are
  // merged into one (vertex colours), lit per vertex by one light from the viewer's side
  // (ambient 0.35 + 0.75 |n·l|): a fragment costs what an unlit one does
  var shaded = new THREE.ShaderMaterial({ vertexColors: true, side: THREE.DoubleSide,
    uniforms: { lightDir: { value: new THREE.Vector3(0.3, 0.6, 1.0).normalize() } },
    vertexShader: "uniform vec3 lightDir; varying vec3 vColor; void main() {" +
      " vec3 n = normalize(normalMatrix * normal);" +
      " vColor = color * (0.35 + 0.75 * abs(dot(n, lightDir)));" +
      " gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }",
    fragmentShader: "varying vec3 vColor;" +
      " void main() { gl_FragColor = linearToOutputTexel(vec4(vColor, 1.0)); }" });
  var nodes = paths.map(function (p) { return viewer.scene_tree.find(p); });
  // mesh files (not primitives) simplified by vertex clustering: the vertices in one cube of
  // CELL × the robot's size become one (mean position, colour and normal) and the triangles
  // that collapse are dropped; a CAD mesh's triangles far below a pixel cost the most
  var CELL = 0.006;
  function cluster(pos, nor, col, idx, fine, cell) {
    var n = fine.length, of = new Int32Array(n), keys = new Map(), m = 0, sums = [];
    for (var i = 0; i < n; i++) {
      var key = fine[i] ? Math.round(pos[3 * i] / cell) + "," + Math.round(pos[3 * i + 1] / cell) +
        "," + Math.round(pos[3 * i + 2] / cell) : "v" + i;
      var k = keys.get(key);
      if (k === undefined) { k = m++; keys.set(key, k); sums.push(new Float64Array(10)); }
      of[i] = k;
      var s = sums[k];
      for (var c = 0; c < 3; c++) {
        s[c] += pos[3 * i + c]; s[3 + c] += nor[3 * i + c]; s[6 + c] += col[3 * i + c];
      }
      s[9] += 1;
    }
    var P = new Float32Array(3 * m), N = new Float32Array(3 * m), C = new Float32Array(3 * m);
    for (var k = 0; k < m; k++) {
      var s = sums[k], l = Math.hypot(s[3], s[4], s[5]) || 1;
      for (var c = 0; c < 3; c++) {
        P[3 * k + c] = s[c] / s[9]; N[3 * k + c] = s[3 + c] / l; C[3 * k + c] = s[6 + c] / s[9];
      }
    }
    var out = [];
    for (var t = 0; t < idx.length; t += 3) {
      var a = of[idx[t]], b = of[idx[t + 1]], c = of[idx[t + 2]];
      if (a !== b && b !== c && a !== c) { out.push(a, b, c); }
    }
    return [P, N, C, new Uint32Array(out)];
  }
  // a flat background (meshcat's gradient is one more full-screen textured pass per frame)
  viewer.scene.background = new THREE.Color(0xd2d8e2);
  DATA.visuals.forEach(function (v, k) {
    place(viewer.scene_tree.find(split(v)), DATA.init, 12 * k);
  });
  viewer.scene.updateMatrixWorld(true);
  var lambert = function (m, colors) {
    return new THREE.MeshLambertMaterial({ color: colors ? 0xffffff : m.color,
      vertexColors: colors, transparent: m.transparent, opacity: m.opacity, side: m.side });
  };
  DATA.groups.forEach(function (g, gi) {
    var anchor = nodes[gi].object, solid = [];
    g.forEach(function (k) {
      var meshes = [];
      viewer.scene_tree.find(split(DATA.visuals[k])).object.traverse(function (o) {
        if (o.isMesh) { meshes.push(o); }
      });
      meshes.forEach(function (m) {
        anchor.attach(m);  // its pose kept, now relative to the group's node
        var mat = m.material;
        if (mat && mat.isMaterial && !mat.map && !mat.transparent &&
            m.geometry.getAttribute("position") && m.geometry.getAttribute("normal")) {
          solid.push(m);
        }
        else if (mat && mat.type === "MeshPhongMaterial" && !mat.map) {
          m.material = lambert(mat, false);
        }
      });
    });
    var nv = 0, ni = 0;
    solid.forEach(function (m) {  // spheres and cylinders: 16 segments around (a joint's
      var g = m.geometry, p = g.parameters || {};  // ball is a few pixels wide)
      if (g.type === "SphereGeometry" && p.widthSegments > 16) {
        m.geometry = new THREE.SphereGeometry(p.radius, 16, 10, p.phiStart, p.phiLength,
                                              p.thetaStart, p.thetaLength);
      }
      else if (g.type === "CylinderGeometry" && p.radialSegments > 16) {
        m.geometry = new THREE.CylinderGeometry(p.radiusTop, p.radiusBottom, p.height, 16,
          p.heightSegments, p.openEnded, p.thetaStart, p.thetaLength);
      }
    });
    solid.forEach(function (m) {
      var n = m.geometry.attributes.position.count;
      nv += n; ni += m.geometry.index ? m.geometry.index.count : n;
    });
    if (!solid.length) { return; }
    var pos = new Float32Array(3 * nv), nor = new Float32Array(3 * nv);
    var col = new Float32Array(3 * nv), idx = new Uint32Array(ni), ov = 0, oi = 0;
    // positions may be quantised (Int16, scaled by the mesh's matrix): read as numbers,
    // written as float32 in the group's frame
    var unit = function (attr) {
      if (!attr.normalized) { return 1; }
      var a = attr.array;
      return a instanceof Int8Array ? 1 / 127 : a instanceof Uint8Array ? 1 / 255 :
        a instanceof Int16Array ? 1 / 32767 : a instanceof Uint16Array ? 1 / 65535 : 1;
    };
    var v3 = new THREE.Vector3(), n3 = new THREE.Matrix3(), fine = new Uint8Array(nv);
    solid.forEach(function (m) {
      m.updateMatrix(); n3.getNormalMatrix(m.matrix);
      fine.fill(m.geometry.type === "BufferGeometry" ? 1 : 0, ov,
                ov + m.geometry.attributes.position.count);
      var geo = m.geometry, P = geo.attributes.position, N = geo.attributes.normal;
      var n = P.count, c = m.material.color, up = unit(P), un = unit(N);
      var vc = m.material.vertexColors && geo.getAttribute("color");
      var uc = vc ? unit(vc) : 1;
      for (var i = 0; i < n; i++) {
        var j = 3 * (ov + i);
        v3.set(P.getX(i) * up, P.getY(i) * up, P.getZ(i) * up).applyMatrix4(m.matrix);
        pos[j] = v3.x; pos[j + 1] = v3.y; pos[j + 2] = v3.z;
        v3.set(N.getX(i) * un, N.getY(i) * un, N.getZ(i) * un).applyMatrix3(n3).normalize();
        nor[j] = v3.x; nor[j + 1] = v3.y; nor[j + 2] = v3.z;
        col[j] = vc ? vc.getX(i) * uc : c.r; col[j + 1] = vc ? vc.getY(i) * uc : c.g;
        col[j + 2] = vc ? vc.getZ(i) * uc : c.b;
      }
      var ix = geo.index, cnt = ix ? ix.count : n;
      for (var t = 0; t < cnt; t++) { idx[oi + t] = ov + (ix ? ix.getX(t) : t); }
      ov += n; oi += cnt; m.parent.remove(m);
    });
    var cut = cluster(pos, nor, col, idx, fine, DATA.scale * CELL);
    var merged = new THREE.BufferGeometry();
    merged.setAttribute("position", new THREE.BufferAttribute(cut[0], 3));
    merged.setAttribute("normal", new THREE.BufferAttribute(cut[1], 3));
    merged.setAttribute("color", new THREE.BufferAttribute(cut[2], 3));
    merged.setIndex(new THREE.BufferAttribute(cut[3], 1));
    var one = new THREE.Mesh(merged, shaded);
    one.name = "merged"; anchor.add(one);
  });
  // overlays: support polygon, CoM, target
  var group = new THREE.Group();
  var polyGeom = new THREE.BufferGeometry();
  polyGeom.setAttribute("position", new THREE.BufferAttribute(new Float32Array(3 * 17), 3));
  var polyMat = new THREE.LineBasicMaterial({ color: 0x2288ff });
  var poly = new THREE.Line(polyGeom, polyMat);
  var dot = function (color, r) {
    return new THREE.Mesh(new THREE.SphereGeometry(r, 16, 12),
                          new THREE.MeshBasicMaterial({ color: color }));
  };
  var com = dot(0x22aa22, DATA.scale * 0.04), target = dot(0xff8800, DATA.scale * 0.03);
  var comGround = dot(0x22aa22, DATA.scale * 0.025);
  group.add(poly); group.add(com); group.add(comGround); group.add(target);
  target.visible = false;
  var footDot = dot(0x22aa22, DATA.scale * 0.022);  // red when near a singularity
  group.add(footDot);
  var zmpDot = dot(0x8844cc, DATA.scale * 0.03);  // the ZMP on the ground, red when outside
  group.add(zmpDot); zmpDot.visible = false;
  // the chain on the nearest singular family (its frames' origins), drawn when near
  var ghostGeom = new THREE.BufferGeometry();
  ghostGeom.setAttribute("position", new THREE.BufferAttribute(new Float32Array(3 * 64), 3));
  var ghost = new THREE.Line(ghostGeom, new THREE.LineBasicMaterial({ color: 0xdd00dd }));
  ghost.visible = false; group.add(ghost);
  viewer.scene_tree.find(["meshcat", "drive"]).set_object(group);
  var renders = [], origRender = viewer.render.bind(viewer), continuous = false;
  viewer.render = function () {
    renders.push(performance.now()); if (renders.length > 600) { renders.shift(); }
    origRender();
  };
  var states = [], fullRatio = window.devicePixelRatio || 1, ratio = fullRatio, adaptAt = 0;
  var good = 0, fixed = false;
  function count(times, now, span) {  // per second, over the last span [ms]
    var n = 0;
    for (var i = times.length - 1; i >= 0 && times[i] > now - span; i--) { n++; }
    return n * 1000 / span;
  }
  function adapt(now) {  // each second: the resolution for >= 30 frames/s while moving
    if (fixed || now - adaptAt < 1000) { return; }
    adaptAt = now;
    // rates over 2 s: one stall of a loaded machine is not a slow page
    var drawn = count(renders, now, 2000);
    var wanted = continuous ? 60 : Math.min(count(states, now, 2000), 60);
    if (wanted < 30) { return; }  // a still scene: nothing to keep up with
    if (drawn < 28 && ratio > 0.25) {  // a frame's cost goes with its pixels: ratio²
      ratio = Math.max(0.25, ratio * Math.max(0.5, Math.min(0.9, Math.sqrt(drawn / 40))));
    }
    else if (drawn >= 0.9 * Math.min(wanted, 50) && ratio < fullRatio && ++good >= 2) {
      ratio = Math.min(fullRatio, ratio / 0.85);  // after 2 s with room to spare
    }
    else { if (drawn < 0.9 * Math.min(wanted, 50)) { good = 0; } return; }
    good = 0;
    renderer.setPixelRatio(ratio); viewer.set_3d_pane_size(); viewer.set_dirty();
  }
  (function spin() {
    if (continuous) { viewer.set_dirty(); }
    adapt(performance.now());
    requestAnimationFrame(spin);
  })();
  el("hk-title").textContent = DATA.title;
  el("hk-pushn").textContent = DATA.push.toFixed(1) + " N";
  var api = { viewer: viewer, state: null, seq: 0, latencies: [], motion: [], errors: [],
              replies: [], ready: false, pushes: [],
              overlays: { zmp: zmpDot, ghost: ghost, com: com, polygon: poly } };
  window.hexapodKin = api;
  var ws = new WebSocket("ws://" + location.host + "/ws");
  var nextId = 1;
  function send(msg) {
    msg.id = nextId++;
    if (ws.readyState === 1) { ws.send(JSON.stringify(msg)); }
    return msg.id;
  }
  api.send = send;
  api.sendRaw = function (text) { ws.send(text); };
  api.fps = function (span) {
    span = span || 1000;
    var now = performance.now(), n = 0;
    for (var i = renders.length - 1; i >= 0 && renders[i] > now - span; i--) { n++; }
    return n * 1000 / span;
  };
  api.setContinuous = function (on) { continuous = !!on; };
  api.resolution = function () { return ratio; };  // the adapted pixel ratio
  api.fixResolution = function (r) {  // a fixed pixel ratio (screenshots); null: adapt again
    fixed = r !== null && r !== undefined;
    ratio = fixed ? r : fullRatio;
    renderer.setPixelRatio(ratio); viewer.set_3d_pane_size(); viewer.set_dirty();
  };
  // modes
  var modes = !DATA.legged ? ["joints", "target"] : DATA.physics ?
    ["joints", "target", "body", "walk", "physics"] : ["joints", "target", "body", "walk"];
  modes.forEach(function (m) {
    var b = document.createElement("button"); b.textContent = m; b.id = "hk-mode-" + m;
    b.onclick = function () { send({ type: "mode", mode: m }); showMode(m); };
    el("hk-modes").appendChild(b);
  });
  var shown = null;
  function showMode(m) {
    if (m === shown) { return; }
    shown = m;
    modes.forEach(function (k) {
      el("hk-tab-" + k).className = "hk-tab" + (k === m ? " on" : "");
      el("hk-mode-" + k).className = k === m ? "on" : "";
    });
    if (m === "target" && api.state && !el("hk-tx").value) {  // start from the foot
      var p = api.state.readout.point;
      ["hk-tx", "hk-ty", "hk-tz"].forEach(function (id, i) { el(id).value = p[i].toFixed(4); });
    }
  }
  // joint sliders
  var sliders = [];
  DATA.joints.forEach(function (j, i) {
    var row = document.createElement("div");
    row.innerHTML = '<span style="display:inline-block;width:110px">' + j.name + '</span>';
    var s = document.createElement("input");
    s.type = "range"; s.min = j.lower; s.max = j.upper; s.step = "any"; s.value = j.value;
    s.id = "hk-joint-" + i; s.dataset.name = j.name;
    var v = document.createElement("span"); v.id = "hk-jv-" + i;
    s.oninput = function () { send({ type: "joint", name: j.name, value: parseFloat(s.value) }); };
    row.appendChild(s); row.appendChild(v); el("hk-joints").appendChild(row); sliders.push([s, v]);
  });
  // feet
  DATA.feet.forEach(function (f, i) {
    var o = document.createElement("option");
    o.value = i; o.textContent = f; el("hk-foot").appendChild(o);
  });
  el("hk-foot").onchange = function () {
    send({ type: "foot", foot: parseInt(el("hk-foot").value, 10) });
  };
  function goTarget(p) {
    send({ type: "target", xyz: p }); showMode("target");
  }
  el("hk-go").onclick = function () {
    goTarget(["hk-tx", "hk-ty", "hk-tz"].map(function (id) { return parseFloat(el(id).value); }));
  };
  // shift+click: a target on the horizontal plane through the current foot point
  var ray = new THREE.Raycaster();
  var downAt = null;
  window.addEventListener("pointerup", function (ev) {  // the view's controls capture it
    // physics mode: a click (not a drag of the view) pushes the robot along the view
    if (!downAt || shown !== "physics" ||
        Math.hypot(ev.clientX - downAt[0], ev.clientY - downAt[1]) > 4) {
      downAt = null; return;
    }
    downAt = null;
    var d = new THREE.Vector3();
    viewer.camera.getWorldDirection(d);
    var root = viewer.scene_tree.find(["meshcat"]).object;
    root.updateMatrixWorld();
    var inv = new THREE.Matrix3().setFromMatrix4(root.matrixWorld).invert();
    d.applyMatrix3(inv);
    var n = Math.hypot(d.x, d.y);
    if (n < 1e-9) { return; }
    api.pushes.push(send({ type: "push", force: [DATA.push * d.x / n, DATA.push * d.y / n] }));
  });
  viewer.renderer.domElement.addEventListener("pointerdown", function (ev) {
    downAt = [ev.clientX, ev.clientY];
    if (!ev.shiftKey || !api.state) { return; }
    var rect = ev.target.getBoundingClientRect();
    var ndc = new THREE.Vector2((ev.clientX - rect.left) / rect.width * 2 - 1,
                                -(ev.clientY - rect.top) / rect.height * 2 + 1);
    ray.setFromCamera(ndc, viewer.camera);
    var root = viewer.scene_tree.find(["meshcat"]).object;
    root.updateMatrixWorld();
    var inv = new THREE.Matrix4().copy(root.matrixWorld).invert();
    var o = ray.ray.origin.clone().applyMatrix4(inv);
    var d = ray.ray.origin.clone().add(ray.ray.direction).applyMatrix4(inv).sub(o);
    var z = (api.state.readout.target || api.state.readout.point)[2];
    if (Math.abs(d.z) < 1e-9) { return; }
    var s = (z - o.z) / d.z;
    goTarget([o.x + s * d.x, o.y + s * d.y, z]);
  });
  // body sliders
  var body = [];
  ["x", "y", "z", "roll", "pitch", "yaw"].forEach(function (n, i) {
    var lim = i < 3 ? DATA.body_shift : DATA.body_angle;
    var row = document.createElement("div");
    row.innerHTML = '<span style="display:inline-block;width:70px">' + n +
      (i < 3 ? " [m]" : " [rad]") + '</span>';
    var s = document.createElement("input");
    s.type = "range"; s.min = -lim; s.max = lim; s.step = "any"; s.value = 0; s.id = "hk-body-" + n;
    var v = document.createElement("span");
    s.oninput = function () {
      var vals = body.map(function (b) { return parseFloat(b[0].value); });
      send({ type: "body", xyz: vals.slice(0, 3), rpy: vals.slice(3) });
    };
    row.appendChild(s); row.appendChild(v); el("hk-body").appendChild(row); body.push([s, v]);
  });
  (function () {  // stance width: a factor of the robot's own reach
    var row = document.createElement("div");
    row.innerHTML = '<span style="display:inline-block;width:70px">stance ×</span>';
    var s = document.createElement("input");
    s.type = "range"; s.min = 0.6; s.max = 1.4; s.step = "any"; s.value = 1; s.id = "hk-stance";
    s.oninput = function () { send({ type: "stance", scale: parseFloat(s.value) }); };
    row.appendChild(s); el("hk-body").appendChild(row);
  })();
  // walking
  DATA.patterns.forEach(function (p) {
    var o = document.createElement("option"); o.textContent = p; el("hk-pattern").appendChild(o);
  });
  DATA.physics_patterns.forEach(function (p) {
    var o = document.createElement("option"); o.textContent = p; el("hk-ppattern").appendChild(o);
  });
  el("hk-pattern").onchange = function () {
    send({ type: "pattern", pattern: el("hk-pattern").value });
  };
  el("hk-ppattern").onchange = function () {
    send({ type: "pattern", pattern: el("hk-ppattern").value });
  };
  var keys = {}, pressAt = null, cmdBefore = null, baseBefore = null;
  function axes() {
    var k = function (c) { return keys[c] ? 1 : 0; };
    return [k("w") - k("s"), k("a") - k("d"), k("q") - k("e")];
  }
  function onKey(ev, down) {
    var c = (ev.key || "").toLowerCase();
    if (!DATA.legged || c === "" || "wasdqe".indexOf(c) < 0) { return; }
    if (ev.target.tagName === "INPUT") { return; }
    if (!!keys[c] === down) { return; }
    keys[c] = down;
    if (down) {
      pressAt = performance.now();
      cmdBefore = api.state ? JSON.stringify(api.state.readout.command) : null;
      baseBefore = api.state ? api.state.readout.base : null;
    }
    send({ type: "drive", axes: axes() });
    if (shown !== "physics") { showMode("walk"); }
  }
  // on-screen joystick: up/down = forward/back, left/right = turn (Q/E)
  var stick = el("hk-stick"), knob = el("hk-knob"), sticking = false, lastSent = "";
  function stickAt(ev, done) {
    var r = stick.getBoundingClientRect(), R = r.width / 2;
    var dx = done ? 0 : (ev.clientX - r.left - R) / R, dy = done ? 0 : (ev.clientY - r.top - R) / R;
    var n = Math.hypot(dx, dy);
    if (n > 1) { dx /= n; dy /= n; }
    knob.style.left = (30 + 30 * dx) + "px"; knob.style.top = (30 + 30 * dy) + "px";
    var axes = [Math.round(-20 * dy) / 20, 0, Math.round(-20 * dx) / 20];  // steps of 0.05
    if (done || JSON.stringify(axes) !== lastSent) {
      lastSent = JSON.stringify(axes);
      send({ type: "drive", axes: axes });
    }
  }
  stick.addEventListener("pointerdown", function (ev) {
    sticking = true; stick.setPointerCapture(ev.pointerId); stickAt(ev, false);
  });
  stick.addEventListener("pointermove", function (ev) { if (sticking) { stickAt(ev, false); } });
  stick.addEventListener("pointerup", function (ev) { sticking = false; stickAt(ev, true); });
  window.addEventListener("keydown", function (ev) { onKey(ev, true); });
  window.addEventListener("keyup", function (ev) { onKey(ev, false); });
  // downloads
  function download(name, text, type) {
    var a = document.createElement("a");
    a.href = URL.createObjectURL(new Blob([text], { type: type }));
    a.download = name; document.body.appendChild(a); a.click(); a.remove();
  }
  var wantDownload = null;
  el("hk-reset").onclick = function () {
    send({ type: "reset" }); body.forEach(function (b) { b[0].value = 0; });
  };
  el("hk-json").onclick = function () { wantDownload = "json"; send({ type: "session" }); };
  el("hk-csv").onclick = function () { wantDownload = "csv"; send({ type: "session" }); };
  var fmt = function (a, n) { return a.map(function (x) { return x.toFixed(n); }).join(" "); };
  function moved(b0, b1) {
    if (!b0) { return false; }
    for (var i = 0; i < 3; i++) { if (Math.abs(b0[i][3] - b1[i][3]) > 1e-9) { return true; } }
    return false;
  }
  var shownText = {};
  function put(id, text) {  // the panel's text changed only when it changed (no relayout)
    if (shownText[id] !== text) { shownText[id] = text; el(id).textContent = text; }
  }
  function onState(st) {
    st.readout.time = st.time; api.state = st; api.seq = st.seq;
    var r = st.readout, now = performance.now();
    states.push(now); if (states.length > 120) { states.shift(); }
    var P = st.poses;  // each group's 3×4 [R | p], column-major: 12 numbers
    for (var k = 0; k < nodes.length; k++) { place(nodes[k], P, 12 * k); }
    if (pressAt !== null && JSON.stringify(r.command) !== cmdBefore) {
      api.latencies.push(now - pressAt); cmdBefore = "seen";
    }
    if (pressAt !== null && moved(baseBefore, r.base)) {
      api.motion.push(now - pressAt); pressAt = null;
    }
    showMode(r.mode);
    put("hk-fk", r.fk.map(function (row) {
      return row.map(function (x) { return x.toFixed(12); }).join(" ");
    }).join("\\n"));
    var fam = r.family ? ("nearest singular family " + r.family.name + ": " +
      r.family.distance.toFixed(4) + " rad" + (r.family.near && r.family.ghost ?
      " (drawn: the chain on it, magenta)" : "")) : "singular families: " + DATA.families;
    ghost.visible = !!(r.family && r.family.near && r.family.ghost);
    if (ghost.visible) {
      var g = r.family.ghost, ga = ghostGeom.attributes.position.array;
      for (var gi = 0; gi < g.length && gi < 64; gi++) {
        ga[3 * gi] = g[gi][0]; ga[3 * gi + 1] = g[gi][1]; ga[3 * gi + 2] = g[gi][2];
      }
      ghostGeom.setDrawRange(0, Math.min(g.length, 64));
      ghostGeom.attributes.position.needsUpdate = true; ghostGeom.computeBoundingSphere();
    }
    put("hk-status", r.foot + " at " + fmt(r.point, 4) + " m\\nσ_min " +
      r.sigma_min.toExponential(3) + " m · manipulability " + r.manipulability.toExponential(3) +
      "\\n" + fam + "\\nstatus: " + r.status);
    put("hk-msg", r.message || "");
    DATA.joints.forEach(function (j, i) {
      if (document.activeElement !== sliders[i][0]) { sliders[i][0].value = r.q[i]; }
      put("hk-jv-" + i, " " + r.q[i].toFixed(3));
    });
    var near = r.sigma_min < DATA.sigma_eps || (r.family && r.family.distance < 0.05);
    footDot.position.set(r.point[0], r.point[1], r.point[2]);
    footDot.material.color.setHex(near ? 0xff0000 : 0x22aa22);
    el("hk-status").style.color = near ? "#d00" : "";
    target.visible = !!r.target;
    if (r.target) { target.position.set(r.target[0], r.target[1], r.target[2]); }
    if (r.support) {
      var s = r.support, pts = [];
      s.feet.forEach(function (p, i) { if (s.stance[i]) { pts.push(p); } });
      var c = [0, 0];
      pts.forEach(function (p) { c[0] += p[0] / pts.length; c[1] += p[1] / pts.length; });
      pts.sort(function (a, b) {
        return Math.atan2(a[1] - c[1], a[0] - c[0]) - Math.atan2(b[1] - c[1], b[0] - c[0]);
      });
      var arr = polyGeom.attributes.position.array, n = Math.min(pts.length, 16);
      var zmin = Math.min.apply(null, s.feet.map(function (p) { return p[2]; }));
      for (var i = 0; i <= 16; i++) {
        var p = pts[n ? (Math.min(i, n) % n) : 0] || [0, 0, 0];
        arr[3 * i] = p[0]; arr[3 * i + 1] = p[1]; arr[3 * i + 2] = zmin;
      }
      polyGeom.attributes.position.needsUpdate = true; polyGeom.computeBoundingSphere();
      var lost = s.margin < 0;
      polyMat.color.setHex(lost ? 0xff0000 : 0x2288ff);
      com.position.set(s.com[0], s.com[1], s.com[2]);
      comGround.position.set(s.com[0], s.com[1], zmin);
      put("hk-margin", (1000 * s.margin).toFixed(1) + " mm" + (lost ? " LOST" : ""));
      el("hk-margin").className = lost ? "lost" : "";
      put("hk-com", fmt(s.com, 3) + " m");
      var zlost = s.zmp_margin !== null && s.zmp_margin < 0;
      put("hk-zmp", s.zmp_margin === null ? "-" :
        (1000 * s.zmp_margin).toFixed(1) + " mm" + (zlost ? " LOST" : ""));
      el("hk-zmp").className = zlost ? "lost" : "";
      zmpDot.visible = !!s.zmp;
      if (s.zmp) { zmpDot.position.set(s.zmp[0], s.zmp[1], s.zmp[2]); }
      zmpDot.material.color.setHex(zlost ? 0xff0000 : 0x8844cc);
      put("hk-cmd", fmt(r.command, 3) + " (vx, vy [m/s], wz [rad/s])");
      put("hk-act", fmt(r.actual, 3));
      put("hk-pcmd", el("hk-cmd").textContent);
      put("hk-pact", fmt(r.actual, 3) + " (vx, vy [m/s], wz [rad/s])");
      put("hk-minm", r.min_margin === null ? "-" : (1000 * r.min_margin).toFixed(1) + " mm");
      var pick = r.mode === "physics" ? "hk-ppattern" : "hk-pattern";
      if (document.activeElement !== el(pick)) { el(pick).value = r.pattern; }
    }
    viewer.set_dirty();
  }
  ws.onopen = function () { el("hk-conn").textContent = "live"; api.ready = true; };
  ws.onclose = function () { el("hk-conn").textContent = "disconnected"; api.ready = false; };
  ws.onmessage = function (ev) {
    var m = JSON.parse(ev.data);
    if (m.type === "state") { onState(m); return; }
    if (m.type === "error") {
      api.errors.push(m); el("hk-msg").textContent = "refused: " + m.error; return;
    }
    if (m.type === "session" && wantDownload) {
      if (wantDownload === "json") {
        download("session.json", JSON.stringify(m.session), "application/json");
      }
      else if (m.timeline) { download("timeline.csv", m.timeline, "text/csv"); }
      else { el("hk-msg").textContent = m.refused; }
      wantDownload = null;
    }
    api.replies.push(m); if (api.replies.length > 50) { api.replies.shift(); }
  };
  if (!DATA.legged) { el("hk-legged").style.display = "none"; }
  showMode("joints");
})();
</script>
"""


def _limits(lo: float, hi: float) -> tuple[float, float]:
    return (lo if math.isfinite(lo) else -math.pi), (hi if math.isfinite(hi) else math.pi)


def drive_page(cockpit: Cockpit, scene: Scene, *, title: str | None = None) -> str:
    """The cockpit's page for one robot (served by :class:`~.server.DriveServer`).

    Raises:
        OptionalDependencyError: meshcat is missing.
        ViewerError: The visual geometry cannot be built.

    """
    model = cockpit.model
    cmds = scene_commands(model, [0.0], cockpit.q[None], base_poses=cockpit.base, trace_frame=False)
    span = float(cockpit.body.leg_span) if cockpit.legged else float(cockpit.limbs[0].max_reach)
    joints = []
    for i, name in enumerate(model.joint_names):
        lo, hi = _limits(float(model.lower[i]), float(model.upper[i]))
        joints.append({"name": name, "lower": lo, "upper": hi, "value": float(cockpit.q[i])})
    fams = cockpit.families
    groups = visual_groups(scene)
    label = title or f"hexapod_kin drive: {model.name}"
    data = {
        "title": label,
        "scene": [base64.b64encode(pack(c)).decode("ascii") for c in cmds],
        "visuals": [v.path for v in scene.visuals],
        "groups": groups,
        "init": _flat(scene.placements(cockpit.q[None], cockpit.base[None])[0]),
        "joints": joints,
        "feet": list(cockpit.body.leg_names) if cockpit.legged else [str(model.tip)],
        "legged": cockpit.legged,
        "physics": cockpit.legged,
        "patterns": list(cockpit.patterns),
        "physics_patterns": list(cockpit.physics_patterns),
        "body_shift": BODY_SHIFT * span,
        "body_angle": BODY_ANGLE,
        "scale": span,
        "sigma_eps": SIGMA_EPS,
        "push": PUSH_WEIGHTS[kind_of(cockpit.body)] * float(cockpit.body.mass) * 9.81
        if cockpit.legged
        else 0.0,
        "families": "per leg: the leg being moved (joints mode), once derived"
        if cockpit.legged
        else (fams.reason or "none")
        if fams is not None
        else "deriving…",
    }
    return page(label, fill(_BODY, data=script_json(data)), style=_STYLE, policy=_CSP)


def visual_groups(scene: Scene) -> list[list[int]]:
    """The scene's visuals (indices) grouped by the joint that carries them, in order.

    The visuals of one group are rigid together: the page places a group by its first one's
    pose (:func:`state_frame` sends one pose per group) and merges its meshes into one.
    """
    joint_of = [int(scene.geom.geometryObjects[k].parentJoint) for k in scene.kept]
    first: dict[int, list[int]] = {}
    for i, j in enumerate(joint_of):
        first.setdefault(j, []).append(i)
    return list(first.values())


def _flat(poses: np.ndarray) -> list[float]:
    """(G, 4, 4) poses as 12 numbers each (3×4 [R | p], column-major; rows 0 0 0 1 not sent)."""
    return np.round(np.transpose(poses[:, :3, :], (0, 2, 1)).reshape(-1), 7).tolist()


def _clean(value: Any) -> Any:
    """JSON-safe: non-finite numbers become None (JSON has no inf or NaN)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def state_frame(cockpit: Cockpit, scene: Scene, seq: int) -> dict[str, Any]:
    """The state message of one tick: the visual groups' poses and the readout.

    Each group's pose (:func:`visual_groups`) is its first visual's, 3×4 column-major.
    """
    with cockpit.lock:
        q, base = cockpit.q.copy(), cockpit.base.copy()
        readout = cockpit.readout()
    poses = scene.placements(q[None], base[None])[0]
    anchors = [g[0] for g in visual_groups(scene)]
    return {"type": "state", "seq": seq, "poses": _flat(poses[anchors]), "readout": _clean(readout)}
