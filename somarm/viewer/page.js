// somarm's text overlay on a meshcat page: a panel saying what the scene shows, and labels pinned
// to scene nodes. Python sends "somarm_text" commands (somarm/viewer/text.py says what each field
// means); every other command goes to meshcat as before.
var SomarmOverlay = (function () {
  "use strict";
  const state = {title: "", lines: [], timeline: null, caption: [], key: [], labels: [], status: "",
                 closed: ""};
  let viewer = null;
  let shownFrame = -1;
  const panel = {};
  const labelNodes = [];

  function element(tag, className, parent) {
    const node = document.createElement(tag);
    if (className) node.className = className;
    if (parent) parent.appendChild(node);
    return node;
  }

  function build() {
    const root = element("div", "somarm-panel", document.body);
    root.id = "somarm-panel";
    panel.status = element("div", "somarm-status", root);
    panel.title = element("div", "somarm-title", root);
    panel.lines = element("div", "somarm-lines", root);
    panel.caption = element("div", "somarm-caption", root);
    panel.key = element("div", "somarm-key", root);
    panel.labels = element("div", "somarm-labels", document.body);
  }

  function fill(box, lines) {
    box.textContent = "";
    for (const line of lines) element("div", "", box).textContent = line;
    box.style.display = lines.length ? "" : "none";
  }

  function renderStatic() {
    const status = state.closed || state.status;
    panel.status.textContent = status;
    panel.status.style.display = status ? "" : "none";
    panel.title.textContent = state.title;
    fill(panel.lines, state.lines);
    panel.key.textContent = "";
    for (const [color, meaning] of state.key) {
      const item = element("span", "somarm-key-item", panel.key);
      element("span", "somarm-swatch", item).style.background = color;
      element("span", "", item).textContent = meaning;
    }
    panel.key.style.display = state.key.length ? "" : "none";
    panel.labels.textContent = "";
    labelNodes.length = 0;
    for (const [path, text] of state.labels) {
      const node = element("div", "somarm-label", panel.labels);
      node.textContent = text;
      labelNodes.push([path.split("/").filter((p) => p.length), node]);
    }
    shownFrame = -1;
    renderCaption();
  }

  // The frame of the playing clip (0 when there is none): what the timeline's lines follow.
  function animationFrame(fps) {
    const actions = viewer.animator.actions;
    if (!actions.length) return 0;
    const time = actions.reduce((longest, action) => Math.max(longest, action.time), 0);
    return Math.floor(time * fps + 1e-6);
  }

  function renderCaption() {
    if (state.timeline && state.timeline.frames.length) {
      const frame = animationFrame(state.timeline.fps);
      if (frame === shownFrame) return;
      shownFrame = frame;
      let lines = [];
      for (const [start, text] of state.timeline.frames) {
        if (start > frame) break;
        lines = text;
      }
      fill(panel.caption, lines.concat(state.caption));
    } else {
      fill(panel.caption, state.caption);
    }
  }

  // The node at a path, or null: unlike scene_tree.find this never creates nodes.
  function nodeAt(parts) {
    let node = viewer.scene_tree;
    for (const name of parts) {
      node = node.children[name];
      if (node === undefined) return null;
    }
    return node.object;
  }

  function placeLabels() {
    if (!labelNodes.length) return;
    const THREE = MeshCat.THREE;
    const width = viewer.renderer.domElement.clientWidth, height = viewer.renderer.domElement.clientHeight;
    viewer.scene.updateMatrixWorld(true);
    for (const [parts, node] of labelNodes) {
      const object = nodeAt(parts);
      if (object === null) { node.style.display = "none"; continue; }
      const point = new THREE.Vector3().setFromMatrixPosition(object.matrixWorld).project(viewer.camera);
      const visible = point.z < 1 && Math.abs(point.x) <= 1.05 && Math.abs(point.y) <= 1.05;
      node.style.display = visible ? "" : "none";
      node.style.left = ((point.x + 1) / 2 * width).toFixed(1) + "px";
      node.style.top = ((1 - point.y) / 2 * height).toFixed(1) + "px";
    }
  }

  function tick() {
    requestAnimationFrame(tick);
    renderCaption();
    placeLabels();
  }

  function take(command) {
    for (const field of ["title", "lines", "timeline", "caption", "key", "labels", "status"]) {
      if (field in command) state[field] = command[field] === null ? (field === "timeline" ? null : []) : command[field];
    }
    if (command.status === null) state.status = "";
    if (command.title === null) state.title = "";
    renderStatic();
  }

  function install(meshcatViewer) {
    viewer = meshcatViewer;
    build();
    const handle = viewer.handle_command.bind(viewer);
    viewer.handle_command = function (command) {
      if (command.type === "somarm_text") take(command);
      else handle(command);
    };
    renderStatic();
    requestAnimationFrame(tick);
  }

  // A live page: say so when the server goes away (training over and the command ended, or Ctrl-C).
  function watch(connection) {
    connection.addEventListener("close", function () {
      state.closed = "connection closed: the viewer's server has stopped (this page shows its last state)";
      renderStatic();
    });
  }

  return {install: install, watch: watch, state: state};
})();
