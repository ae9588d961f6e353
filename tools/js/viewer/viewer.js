// spall's debris viewer: plays the run's debris.glb, inlined in the page as base64, with three.js.
// Bundled by esbuild at build time (CMakeLists.txt) and embedded in the spall binary, so the page
// spall view writes needs neither a server nor the network.
//
// URL hash: #t=SECONDS shows that moment, paused. For scripts: document.body.dataset.ready is set
// once the debris is loaded, and dataset.shownTime once the frame for a requested time is drawn.
import * as THREE from "three";
import { GLTFLoader } from "three/examples/jsm/loaders/GLTFLoader.js";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";

function inlinedGlb() {
  const text = document.getElementById("spall-debris").textContent.trim();
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return bytes.buffer;
}

// The box holding all but the outermost 1 % of pose samples per axis, as spall render frames it:
// a few fragments thrown far must not shrink the rest to a dot.
function debrisBox(clip) {
  const axes = [[], [], []];
  for (const track of clip.tracks) {
    if (!track.name.endsWith(".position")) continue;
    for (let i = 0; i < track.values.length; ++i) axes[i % 3].push(track.values[i]);
  }
  const box = new THREE.Box3();
  if (axes[0].length === 0) return box.setFromCenterAndSize(new THREE.Vector3(), new THREE.Vector3(1, 1, 1));
  const quantile = (values, q) => values[Math.min(values.length - 1, Math.floor(q * values.length))];
  const lo = [], hi = [];
  for (const values of axes) {
    values.sort((a, b) => a - b);
    lo.push(quantile(values, 0.01));
    hi.push(quantile(values, 0.99));
  }
  box.set(new THREE.Vector3(...lo), new THREE.Vector3(...hi));
  return box.expandByScalar(0.25);
}

function makeStage(canvasParent) {
  const renderer = new THREE.WebGLRenderer({ antialias: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(window.innerWidth, window.innerHeight);
  canvasParent.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xdfe6ee);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x6b5d4f, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 2.2);
  sun.position.set(4, 10, 6);
  scene.add(sun);
  const camera = new THREE.PerspectiveCamera(40, window.innerWidth / window.innerHeight, 0.01, 1e4);
  const controls = new OrbitControls(camera, renderer.domElement);
  window.addEventListener("resize", () => {
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
  });
  return { renderer, scene, camera, controls };
}

function frameBox(stage, box) {
  const centre = box.getCenter(new THREE.Vector3());
  const radius = box.getSize(new THREE.Vector3()).length() / 2;
  const distance = radius / Math.sin(THREE.MathUtils.degToRad(stage.camera.fov / 2));
  const direction = new THREE.Vector3(1.0, 0.55, 1.4).normalize();
  stage.camera.position.copy(centre).addScaledVector(direction, distance);
  stage.controls.target.copy(centre);
  stage.controls.update();
  return radius;
}

// The box of every pose sample, the furthest fragment's included, and of the charges.
function reachBox(clip, charges) {
  const box = new THREE.Box3();
  for (const track of clip ? clip.tracks : []) {
    if (!track.name.endsWith(".position")) continue;
    for (let i = 0; i + 2 < track.values.length; i += 3)
      box.expandByPoint(new THREE.Vector3(track.values[i], track.values[i + 1], track.values[i + 2]));
  }
  for (const charge of charges) box.expandByPoint(charge.position);
  return box;
}

// spall's ground is z = 0, y = 0 in glTF's Y-up frame: a grid of 1 m squares there, centred on
// whole metres, wide enough that every fragment lands on it. Its extent (x0,x1,z0,z1 in metres,
// glTF axes) goes into document.body.dataset.ground for scripts.
function addGround(stage, reach) {
  const margin = 1;  // a centre of mass within 1 m of the grid's edge keeps its piece on the grid
  const cx = Math.round((reach.min.x + reach.max.x) / 2), cz = Math.round((reach.min.z + reach.max.z) / 2);
  const half = Math.max(cx - reach.min.x, reach.max.x - cx, cz - reach.min.z, reach.max.z - cz, 0) + margin;
  const size = 2 * Math.ceil(half);
  const grid = new THREE.GridHelper(size, size, 0x8a8f96, 0xb8bec6);
  grid.position.set(cx, 0, cz);
  stage.scene.add(grid);
  document.body.dataset.ground = [cx - size / 2, cx + size / 2, cz - size / 2, cz + size / 2].join(",");
}

// The glTF's empty nodes with a TNT mass in their extras (spall export gltf writes one per charge).
function chargesOf(gltfScene) {
  const charges = [];
  gltfScene.traverse((o) => {
    if (o.userData && typeof o.userData.tnt_kg === "number") charges.push({ position: o.getWorldPosition(new THREE.Vector3()), tntKg: o.userData.tnt_kg });
  });
  return charges;
}

// Each charge as an orange ball: the TNT's own sphere (density 1600 kg/m3) or, where that would be
// a speck, 1.5 % of the view's size, so it can be found at any zoom.
function addChargeMarkers(stage, charges, viewRadius) {
  const material = new THREE.MeshBasicMaterial({ color: 0xff6e00 });
  for (const charge of charges) {
    const tntRadius = Math.cbrt((3 * charge.tntKg) / (4 * Math.PI * 1600));
    const marker = new THREE.Mesh(new THREE.SphereGeometry(Math.max(tntRadius, 0.015 * viewRadius), 24, 16), material);
    marker.position.copy(charge.position);
    stage.scene.add(marker);
  }
}

function parseHashTime() {
  const match = /t=([0-9.eE+-]+)/.exec(window.location.hash);
  const t = match ? Number(match[1]) : NaN;
  return Number.isFinite(t) ? t : null;
}

function start(gltf, stage) {
  stage.scene.add(gltf.scene);
  const clip = gltf.animations[0];
  const mixer = new THREE.AnimationMixer(gltf.scene);
  const duration = clip ? clip.duration : 0;
  // The viewer keeps the time itself and poses the clip there: the mixer's own clock would wrap
  // at the end or stop the action, and a stopped action ignores a new time.
  const action = clip ? mixer.clipAction(clip).play() : null;
  const charges = chargesOf(gltf.scene);
  const framed = clip ? debrisBox(clip) : new THREE.Box3().setFromObject(gltf.scene);
  for (const charge of charges) framed.expandByPoint(charge.position);
  const viewRadius = frameBox(stage, framed);
  addGround(stage, reachBox(clip, charges));
  addChargeMarkers(stage, charges, viewRadius);

  const slider = document.getElementById("time");
  const label = document.getElementById("time-label");
  const play = document.getElementById("play");
  const speed = document.getElementById("speed");
  slider.max = String(duration);
  slider.step = String(Math.max(duration / 2000, 1e-6));
  let time = 0, playing = true, pendingShownTime = null;

  const show = (t) => {
    time = Math.min(Math.max(t, 0), duration);
    if (action) {
      action.time = time;
      mixer.update(0);
    }
    slider.value = String(time);
    label.textContent = `t = ${time.toFixed(4)} s / ${duration.toFixed(3)} s`;
  };
  const pause = (p) => { playing = !p; play.textContent = playing ? "pause" : "play"; };
  const fromHash = () => {
    const t = parseHashTime();
    if (t === null) return;
    pause(true);
    show(t);
    pendingShownTime = time;
  };
  slider.addEventListener("input", () => { pause(true); show(Number(slider.value)); });
  play.addEventListener("click", () => { if (time >= duration) show(0); pause(playing); });
  window.addEventListener("hashchange", fromHash);
  fromHash();

  const timer = new THREE.Timer();
  stage.renderer.setAnimationLoop((timestamp) => {
    timer.update(timestamp);
    if (playing) {
      show(time + timer.getDelta() * Number(speed.value));
      if (time >= duration) pause(true);
    }
    stage.controls.update();
    stage.renderer.render(stage.scene, stage.camera);
    if (pendingShownTime !== null) {
      document.body.dataset.shownTime = String(pendingShownTime);
      pendingShownTime = null;
    }
  });
  document.getElementById("status").textContent =
    `${gltf.scene.children.length - charges.length} fragments, ${charges.length} charge${charges.length === 1 ? "" : "s"}, ${duration.toFixed(3)} s`;
  document.body.dataset.ready = "1";
}

const stage = makeStage(document.getElementById("stage"));
new GLTFLoader().parse(inlinedGlb(), "", (gltf) => start(gltf, stage), (error) => {
  document.getElementById("status").textContent = `could not read the debris: ${error.message ?? error}`;
  document.body.dataset.error = "1";
});
