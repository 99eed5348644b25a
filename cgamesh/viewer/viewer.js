// cgamesh viewer page script (MIT, part of cgamesh). Reads the JSON in #cgamesh-data and shows
// the meshes with three.js and the CGA objects with ganja.js. It reports its state in #status
// and in document.title ("ready" or "error: ...") for headless tests.
"use strict";
(function () {
  const status = document.getElementById("status");
  const errors = [];
  function fail(message) {
    errors.push(String(message));
    status.textContent = "error: " + errors.join(" | ");
    document.title = "cgamesh viewer: error";
  }
  window.addEventListener("error", (event) => fail(event.message || event.error));
  window.addEventListener("unhandledrejection", (event) => fail(event.reason));

  function decode(b64, Type) {
    const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    return new Type(bytes.buffer);
  }

  function checkerTexture() {
    const size = 512, cells = 8, canvas = document.createElement("canvas");
    canvas.width = canvas.height = size;
    const g = canvas.getContext("2d"), step = size / cells;
    for (let i = 0; i < cells; i++) {
      for (let j = 0; j < cells; j++) {
        const hue = Math.round(360 * i / cells);
        g.fillStyle = (i + j) % 2 ? `hsl(${hue}, 70%, 75%)` : `hsl(${hue}, 70%, 35%)`;
        g.fillRect(i * step, j * step, step, step);
      }
    }
    g.fillStyle = "#ffffff";
    g.font = `${step * 0.45}px sans-serif`;
    g.fillText("u\u2192", step * 0.15, size - step * 0.3);  // bottom-left corner: the UV origin
    const texture = new THREE.CanvasTexture(canvas);
    texture.wrapS = texture.wrapT = THREE.RepeatWrapping;
    texture.colorSpace = THREE.SRGBColorSpace;
    texture.flipY = false;  // glTF convention: V runs down the image, as the exported UVs are stored
    return texture;
  }

  function showMeshes(data) {
    const host = document.getElementById("view");
    const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.setSize(host.clientWidth, host.clientHeight);
    host.appendChild(renderer.domElement);
    const scene = new THREE.Scene();
    scene.background = new THREE.Color(0x2b303a);
    scene.add(new THREE.HemisphereLight(0xdfe8ff, 0x3a3026, 1.2));
    const sun = new THREE.DirectionalLight(0xffffff, 2.0);
    sun.position.set(3, 5, 4);
    scene.add(sun);

    const checker = checkerTexture();
    const materials = [], normalLines = new THREE.Group(), box = new THREE.Box3();
    let vertices = 0, triangles = 0;
    for (const s of data.surfaces) {
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute("position", new THREE.BufferAttribute(decode(s.positions, Float32Array), 3));
      geometry.setAttribute("normal", new THREE.BufferAttribute(decode(s.normals, Float32Array), 3));
      geometry.setAttribute("uv", new THREE.BufferAttribute(decode(s.uvs, Float32Array), 2));
      geometry.setIndex(new THREE.BufferAttribute(decode(s.indices, Uint32Array), 1));
      if (s.colors) geometry.setAttribute("color", new THREE.BufferAttribute(decode(s.colors, Float32Array), 3));
      geometry.computeBoundingBox();
      box.union(geometry.boundingBox);
      // vertex colours (linear RGB, as in glTF) replace the material's colour: white multiplies them
      const base = s.colors ? new THREE.Color(1, 1, 1) : new THREE.Color(s.color[0], s.color[1], s.color[2]);
      const material = new THREE.MeshStandardMaterial({
        color: base, roughness: s.roughness, metalness: s.metallic, vertexColors: Boolean(s.colors),
        side: s.double_sided ? THREE.DoubleSide : THREE.FrontSide,
      });
      material.userData.color = material.color.clone();
      materials.push(material);
      const mesh = new THREE.Mesh(geometry, material);
      mesh.name = s.name;
      scene.add(mesh);
      vertices += s.vertices;
      triangles += geometry.index.count / 3;
    }
    const centre = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3()).length() || 1;
    for (const s of data.surfaces) {  // vertex normals as short lines, at most max_normal_lines in all
      const p = decode(s.positions, Float32Array), n = decode(s.normals, Float32Array);
      const count = p.length / 3, every = Math.max(1, Math.ceil(vertices / data.max_normal_lines));
      const lines = new Float32Array(6 * Math.ceil(count / every));
      let k = 0;
      for (let i = 0; i < count; i += every) {
        for (let c = 0; c < 3; c++) {
          lines[k + c] = p[3 * i + c];
          lines[k + 3 + c] = p[3 * i + c] + 0.03 * size * n[3 * i + c];
        }
        k += 6;
      }
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute("position", new THREE.BufferAttribute(lines.subarray(0, k), 3));
      normalLines.add(new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ color: 0x66ddff })));
    }
    normalLines.visible = false;
    scene.add(normalLines);

    const camera = new THREE.PerspectiveCamera(40, host.clientWidth / host.clientHeight, size * 1e-3, size * 100);
    camera.position.copy(centre).add(new THREE.Vector3(0.6, 0.45, 0.9).multiplyScalar(size));
    const controls = new THREE.OrbitControls(camera, renderer.domElement);
    controls.target.copy(centre);
    controls.update();
    const draw = () => renderer.render(scene, camera);
    controls.addEventListener("change", draw);
    window.addEventListener("resize", () => {
      renderer.setSize(host.clientWidth, host.clientHeight);
      camera.aspect = host.clientWidth / host.clientHeight;
      camera.updateProjectionMatrix();
      draw();
    });

    function toggle(button, apply) {
      button.addEventListener("click", () => {
        const on = button.getAttribute("aria-pressed") !== "true";
        button.setAttribute("aria-pressed", String(on));
        apply(on);
        draw();
      });
    }
    toggle(document.getElementById("checker"), (on) => {
      for (const m of materials) {
        m.map = on ? checker : null;
        m.color.copy(on ? new THREE.Color(1, 1, 1) : m.userData.color);
        m.needsUpdate = true;
      }
    });
    toggle(document.getElementById("normals"), (on) => { normalLines.visible = on; });
    document.getElementById("info").textContent =
      `${data.scene}: ${data.surfaces.length} surface(s), ${vertices} vertices, ${triangles} triangles`;
    draw();
  }

  function showCga(data) {
    const host = document.getElementById("cga");
    const objects = data.cga;
    const all = objects.controls.concat(objects.interpolated).flat();
    if (all.length === 0) return;
    // Centre and scale into ganja's default view; conformal maps keep circles circles.
    const lo = [0, 1, 2].map((c) => Math.min(...all.map((p) => p[c])));
    const hi = [0, 1, 2].map((c) => Math.max(...all.map((p) => p[c])));
    const mid = lo.map((l, c) => 0.5 * (l + hi[c]));
    const scale = 4.0 / Math.max(1e-9, ...hi.map((h, c) => h - lo[c]));
    const local = (p) => p.map((x, c) => (x - mid[c]) * scale);
    // CGA G(4,1) through ganja's functional API (no source translation): e4^2 = +1, e5^2 = -1,
    // n_inf = e4 + e5, n_0 = (e5 - e4) / 2, up(x) = n_0 + x + x^2 n_inf / 2.
    const A = Algebra(4, 1);
    const ni = A.Coeff(4, 1, 5, 1), no = A.Coeff(4, -0.5, 5, 0.5);
    const up = (p) => {
      const q = local(p);
      return no.Add(A.Coeff(1, q[0], 2, q[1], 3, q[2])).Add(ni.Scale(0.5 * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2])));
    };
    const blade = (points) => points.map(up).reduce((a, b) => a.Wedge(b));
    const items = [0xdd2222].concat(objects.controls.map(blade), [0x2255dd], objects.interpolated.map(blade));
    const graph = A.graph(items, { gl: true, conformal: true, grid: false, scale: 1.0 });
    host.appendChild(graph);
    const button = document.getElementById("cga-toggle");
    button.addEventListener("click", () => {
      const on = button.getAttribute("aria-pressed") !== "true";
      button.setAttribute("aria-pressed", String(on));
      host.style.display = on ? "" : "none";
      document.getElementById("cga-title").style.display = on ? "" : "none";
    });
  }

  try {
    const data = JSON.parse(document.getElementById("cgamesh-data").textContent);
    showMeshes(data);
    showCga(data);
    requestAnimationFrame(() => requestAnimationFrame(() => {
      if (errors.length === 0) {
        status.textContent = "ready";
        document.title = "cgamesh viewer: ready";
      }
    }));
  } catch (error) {
    fail(error && error.stack ? error.stack.split("\n")[0] : error);
  }
})();
