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
  // spall's ground is z = 0, y = 0 in glTF's Y-up frame: a reference grid there.
  const size = Math.max(2, 2 * Math.ceil(radius));
  stage.scene.add(new THREE.GridHelper(size, size, 0x8a8f96, 0xb8bec6));
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
  frameBox(stage, clip ? debrisBox(clip) : new THREE.Box3().setFromObject(gltf.scene));

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
    `${gltf.scene.children.length} fragments, ${duration.toFixed(3)} s`;
  document.body.dataset.ready = "1";
}

const stage = makeStage(document.getElementById("stage"));
new GLTFLoader().parse(inlinedGlb(), "", (gltf) => start(gltf, stage), (error) => {
  document.getElementById("status").textContent = `could not read the debris: ${error.message ?? error}`;
  document.body.dataset.error = "1";
});
