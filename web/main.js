// Drives the page: starts abut's scene (pkg/abut_web.js, built by web/build.sh) with the
// controls' settings, advances it once per animation frame and plots the normal contact force
// against time. Query parameters set the controls and the run's length (the page test uses
// them): ?friction=0.2&scale=1&sliding=finite&beads=1024&frames=300&per_frame=20.
import init, { Page } from "./pkg/abut_web.js";

const $ = (id) => document.getElementById(id);
const query = new URLSearchParams(location.search);
for (const key of ["friction", "scale", "sliding", "beads"]) {
  if (query.has(key)) $(key).value = query.get(key);
}
const FRAMES = Number(query.get("frames") ?? 300);
const PER_FRAME = Number(query.get("per_frame") ?? 20);

let run = 0; // the current run's number: a restart ends the one before
const history = [];
const times = []; // wall time per increment of each frame (ms)

function plot(weight) {
  const c = $("plot"), g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  const [l, r, t, b] = [48, 10, 10, 30];
  const w = c.width - l - r, h = c.height - t - b;
  const tMax = Math.max(FRAMES * PER_FRAME * (history.dt ?? 1e-3), 1e-9);
  const fMax = Math.max(1.5 * weight, ...history.map((p) => p[1]), 1e-9);
  g.strokeStyle = "#888"; g.fillStyle = "#444"; g.font = "11px sans-serif";
  g.strokeRect(l, t, w, h);
  g.fillText("normal contact force (N)", l + 4, t + 12);
  g.fillText("time (s)", l + w - 40, c.height - 4);
  for (let k = 0; k <= 4; k++) {
    g.fillText((fMax * k / 4).toPrecision(2), 4, t + h - h * k / 4 + 4);
    g.fillText((tMax * k / 4).toFixed(2), l + w * k / 4 - 8, t + h + 14);
  }
  const x = (s) => l + w * s / tMax, y = (f) => t + h - h * f / fMax;
  g.setLineDash([4, 4]); g.strokeStyle = "#999";
  g.beginPath(); g.moveTo(l, y(weight)); g.lineTo(l + w, y(weight)); g.stroke();
  g.setLineDash([]); g.strokeStyle = "#d55e00"; g.lineWidth = 1.5;
  g.beginPath();
  history.forEach(([s, f], i) => (i ? g.lineTo(x(s), y(f)) : g.moveTo(x(s), y(f))));
  g.stroke();
}

async function start() {
  const mine = ++run;
  history.length = 0;
  times.length = 0;
  $("error").textContent = "";
  document.body.dataset.state = "running";
  try {
    const page = await Page.start($("scene"), Number($("beads").value), Number($("friction").value),
      Number($("scale").value), $("sliding").value === "small");
    history.dt = page.dt();
    $("legend").textContent = `blue → red: 0 → ${page.pressure_scale()} Pa`;
    const weight = page.weight_normal();
    let last = null;
    for (let frame = 0; frame < FRAMES && mine === run; frame++) {
      last = JSON.parse(await page.advance(PER_FRAME));
      history.push([last.time, last.normal_force]);
      times.push(last.ms_per_increment);
      $("time").value = last.time.toFixed(3);
      $("increments").value = last.increments;
      $("per-increment").value = last.ms_per_increment.toFixed(3);
      $("on-plate").value = last.on_plate;
      $("force").value = last.normal_force.toFixed(3);
      plot(weight);
      await new Promise(requestAnimationFrame);
    }
    if (mine === run) {
      window.abutResult = { ...last, frame_ms_per_increment: times.slice() };
      document.body.dataset.state = "done";
    } else {
      page.free(); // a restart took over the canvas
    }
  } catch (e) {
    $("error").textContent = String(e);
    document.body.dataset.state = "failed";
    console.error("abut page:", e);
  }
}

for (const id of ["friction", "scale"]) {
  $(id).addEventListener("input", () => ($(id + "-out").value = $(id).value));
  $(id + "-out").value = $(id).value;
}
for (const id of ["friction", "scale", "sliding", "beads"]) $(id).addEventListener("change", start);
$("restart").addEventListener("click", start);
await init();
start();
