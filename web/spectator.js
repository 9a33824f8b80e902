// The spectator view of one vistel room (/room/NAME): the room in 3D with three.js r111.
// It opens /ws/room/NAME (with ?token= when the page has one), loads every member's
// avatar as a skinned glTF (/avatar/HASH.glb), and plays the postures the server streams
// (web/PROTOCOL.md) a little behind the server clock, interpolated between the postures
// around that time. Name tags, a free orbit camera and a follow-member camera, the props
// (balls); it says when the room is empty or closed, and reconnects (with a growing,
// jittered wait) when the server goes away.
//
// For tests and tools, window.vistelScene summarises what is on screen (members, their
// motion and screen boxes, props, frames, errors, WebGL state).
'use strict';

(function () {
  const kDelay = 0.1;          // seconds behind the newest server time
  const kMaxSamples = 64;      // postures kept per member
  const kReconnectMin = 0.25;  // seconds
  const kReconnectMax = 4.0;
  const kColors = [0x5b8def, 0xe8794a, 0x59b36b, 0xc265d6, 0xd4b94a, 0x4fc1c7, 0xe25c7a, 0x9a9a9a];

  const roomName = decodeURIComponent(location.pathname.split('/').filter(Boolean).pop() || '');
  const params = new URLSearchParams(location.search);
  const token = params.get('token') || '';
  // Visible spectator (web/PROTOCOL.md): ?visible=1[&name=N] or the "visible" toggle joins
  // the room as a member others see at this page's camera (servers with --web-members).
  const kPoseInterval = 0.1;  // seconds between camera poses sent (10 Hz)
  const visibleName = (params.get('name') || '').slice(0, 64);
  let wantVisible = params.get('visible') === '1';

  // ------------------------------------------------------------------ the summary
  const summary = {
    room: roomName,
    state: 'connecting',
    message: '',
    connected: false,
    connects: 0,
    reconnects: 0,
    framesReceived: 0,
    framesRendered: 0,
    members: [],
    props: [],
    errors: [],
    webgl: { ok: false, renderer: '', contextLost: false, glErrors: 0 },
    camera: 'orbit',
    visible: { wanted: wantVisible, state: 'off', id: 0, name: '', message: '', posesSent: 0 },
  };
  window.vistelScene = summary;
  function recordError(text) {
    if (summary.errors.length < 50) summary.errors.push(String(text).slice(0, 500));
  }
  const consoleError = console.error.bind(console);
  console.error = function (...args) {
    recordError(args.map(String).join(' '));
    consoleError(...args);
  };
  window.addEventListener('error', (e) => recordError('uncaught: ' + (e.message || e)));
  window.addEventListener('unhandledrejection', (e) => recordError('unhandled: ' + e.reason));

  const statusEl = document.getElementById('status');
  document.getElementById('room-name').textContent = roomName;
  document.title = 'vistel: ' + roomName;
  function setStatus(state, message) {
    summary.state = state;
    summary.message = message;
    statusEl.textContent = message;
    statusEl.className = 'banner ' + ({ live: 'live', absent: 'warn', closed: 'warn',
      reconnecting: 'warn', connecting: '', unauthorized: 'error', full: 'error', error: 'error' }[state] || '');
  }

  if (typeof THREE === 'undefined' || !THREE.GLTFLoader || !THREE.OrbitControls) {
    setStatus('error', 'three.js did not load');
    recordError('three.js missing');
    return;
  }

  // ------------------------------------------------------------------ the scene
  const view = document.getElementById('view');
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(view.clientWidth || window.innerWidth, view.clientHeight || window.innerHeight);
  renderer.gammaOutput = true;
  renderer.gammaFactor = 2.2;
  view.appendChild(renderer.domElement);
  const gl = renderer.getContext();
  summary.webgl.ok = !!gl;
  if (gl) {
    summary.webgl.renderer = String(gl.getParameter(gl.RENDERER));
    summary.webgl.version = String(gl.getParameter(gl.VERSION));
  }
  renderer.domElement.addEventListener('webglcontextlost', (e) => {
    e.preventDefault();
    summary.webgl.contextLost = true;
    recordError('WebGL context lost');
  });

  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x2a2e36);
  scene.add(new THREE.HemisphereLight(0xddeeff, 0x3a3530, 0.9));
  const sun = new THREE.DirectionalLight(0xffffff, 0.8);
  sun.position.set(3, 6, 4);
  scene.add(sun);
  const floor = new THREE.Mesh(new THREE.CircleBufferGeometry(8, 64),
    new THREE.MeshStandardMaterial({ color: 0x262a31, roughness: 1.0 }));
  floor.rotation.x = -Math.PI / 2;
  scene.add(floor);
  const grid = new THREE.GridHelper(16, 16, 0x56606e, 0x474f5b);
  grid.position.y = 0.002;
  scene.add(grid);

  const camera = new THREE.PerspectiveCamera(50, 1, 0.05, 200);
  camera.position.set(5.0, 2.6, 2.5);  // from the side: the first two members face each other along Z
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.target.set(0, 1.0, 0);
  controls.enableDamping = true;
  controls.update();

  function resize() {
    const w = view.clientWidth || window.innerWidth;
    const h = view.clientHeight || window.innerHeight;
    renderer.setSize(w, h);
    camera.aspect = w / Math.max(1, h);
    camera.updateProjectionMatrix();
  }
  window.addEventListener('resize', resize);
  resize();

  // ------------------------------------------------------------------ members
  const members = new Map();  // id -> member
  const props = new Map();    // id -> prop
  const tagsEl = document.getElementById('tags');
  const listEl = document.getElementById('members');
  const cameraSelect = document.getElementById('camera');
  const loader = new THREE.GLTFLoader();
  let colorIndex = 0;
  let serverCreatedAt = 0;

  function memberKey(m) { return m.id + '/' + m.name + '/' + (m.avatar || ''); }

  function addMember(info) {
    const m = {
      id: info.id, name: info.name, avatar: info.avatar, key: memberKey(info),
      joinedAt: info.joined_at, seat: info.seat,
      color: kColors[colorIndex++ % kColors.length],
      group: new THREE.Group(), bones: null, head: null, loaded: false, failed: false,
      samples: [], lastSequence: -1, motion: 0, previous: null, screen: null,
      tag: document.createElement('div'), item: document.createElement('li'),
    };
    m.group.position.set(info.seat.x, 0, info.seat.z);
    m.group.rotation.y = info.seat.yaw;
    scene.add(m.group);
    m.tag.className = 'tag';
    m.tag.textContent = info.name;
    tagsEl.appendChild(m.tag);
    listEl.appendChild(m.item);
    const option = document.createElement('option');
    option.value = 'follow:' + info.id;
    option.textContent = 'follow ' + info.name;
    cameraSelect.appendChild(option);
    m.option = option;
    if (info.avatar) loadAvatar(m);
    m.group.visible = m.id !== summary.visible.id;
    members.set(m.id, m);
  }

  function removeMember(m) {
    scene.remove(m.group);
    m.group.traverse((o) => {
      if (o.geometry) o.geometry.dispose();
      if (o.material) o.material.dispose();
    });
    m.tag.remove();
    m.item.remove();
    if (cameraSelect.value === m.option.value) setCamera('orbit');
    m.option.remove();
    m.removed = true;
    members.delete(m.id);
  }

  function loadAvatar(m) {
    loader.load('/avatar/' + m.avatar + '.glb', (gltf) => {
      if (m.removed) return;
      let skinned = null;
      gltf.scene.traverse((o) => {
        if (o.isSkinnedMesh && !skinned) skinned = o;
      });
      if (!skinned) {
        m.failed = true;
        recordError('avatar of ' + m.name + ' has no skin');
        return;
      }
      // An avatar with a look of its own keeps it; a plain one gets the member's colour.
      const json = gltf.parser && gltf.parser.json;
      const plain = !(json && json.materials && json.materials.length > 0);
      gltf.scene.traverse((o) => {
        if (!o.isSkinnedMesh) return;
        o.frustumCulled = false;  // its bounds are the rest pose's
        if (plain) o.material.color.setHex(m.color);
      });
      m.bones = skinned.skeleton.bones;  // skin joints = the skeleton's joint order
      m.head = m.bones.find((b) => /head/i.test(b.name)) || m.bones[m.bones.length - 1];
      m.group.add(gltf.scene);
      m.loaded = true;
    }, undefined, (error) => {
      m.failed = true;
      recordError('avatar of ' + m.name + ': ' + (error && error.message ? error.message : error));
    });
  }

  function onRoster(msg) {
    serverCreatedAt = msg.created_at;
    const seen = new Set();
    for (const info of msg.members) {
      seen.add(info.id);
      const old = members.get(info.id);
      if (old && old.key === memberKey(info) && old.seat.x === info.seat.x &&
          old.seat.z === info.seat.z) {
        continue;
      }
      if (old) removeMember(old);
      addMember(info);
    }
    for (const m of Array.from(members.values())) {
      if (!seen.has(m.id)) removeMember(m);
    }
  }

  function clearRoom() {
    for (const m of Array.from(members.values())) removeMember(m);
    for (const p of props.values()) scene.remove(p.mesh);
    props.clear();
  }

  // ------------------------------------------------------------------ the stream
  let serverOffset = null;  // server time - local time (s), the least delayed seen
  let latestServerTime = 0;

  function localNow() { return performance.now() / 1000; }

  function onFrame(buffer) {
    const v = new DataView(buffer);
    if (v.byteLength < 16 || v.getUint8(0) !== 1 || v.getUint8(1) !== 1) {
      recordError('bad frame');
      return;
    }
    const memberCount = v.getUint16(2, true);
    const propCount = v.getUint16(4, true);
    const serverTime = v.getFloat64(8, true);
    latestServerTime = serverTime;
    const estimate = serverTime - localNow();
    serverOffset = serverOffset === null ? estimate : Math.max(estimate, serverOffset - 0.002);
    let at = 16;
    for (let i = 0; i < memberCount; ++i) {
      const id = v.getUint32(at, true);
      const capture = v.getFloat64(at + 4, true);
      const sequence = v.getUint16(at + 12, true);
      const n = v.getUint8(at + 14);
      const root = [v.getFloat32(at + 16, true), v.getFloat32(at + 20, true), v.getFloat32(at + 24, true)];
      at += 28;
      const q = new Float32Array(n * 4);
      for (let k = 0; k < n * 4; ++k) q[k] = v.getInt16(at + 2 * k, true) / 32767;
      at += n * 8;
      const m = members.get(id);
      if (!m || n === 0 || sequence === m.lastSequence) continue;
      m.lastSequence = sequence;
      const last = m.samples[m.samples.length - 1];
      if (last && capture <= last.t) continue;  // out of order
      m.samples.push({ t: capture, root, q });
      if (m.samples.length > kMaxSamples) m.samples.shift();
    }
    const seen = new Set();
    for (let i = 0; i < propCount; ++i) {
      const id = v.getUint32(at, true);
      const f = (k) => v.getFloat32(at + 4 + 4 * k, true);
      const position = new THREE.Vector3(f(0), f(1), f(2));
      const radius = f(6);
      at += 32;
      seen.add(id);
      let p = props.get(id);
      if (!p) {
        p = { id, mesh: new THREE.Mesh(new THREE.SphereBufferGeometry(1, 24, 16),
          new THREE.MeshStandardMaterial({ color: 0xf0a030, roughness: 0.5 })), samples: [] };
        scene.add(p.mesh);
        props.set(id, p);
      }
      p.mesh.scale.setScalar(radius);
      p.samples.push({ t: serverTime, position });
      if (p.samples.length > 16) p.samples.shift();
    }
    for (const [id, p] of props) {
      if (!seen.has(id)) {
        scene.remove(p.mesh);
        props.delete(id);
      }
    }
    summary.framesReceived++;
  }

  function onText(text) {
    let msg;
    try {
      msg = JSON.parse(text);
    } catch (e) {
      recordError('bad message');
      return;
    }
    if (msg.type === 'hello') {
      // A new connection: the server's clock may have restarted.
      serverOffset = null;
      for (const m of members.values()) {
        m.samples = [];
        m.lastSequence = -1;
      }
    } else if (msg.type === 'member') {
      onMemberState(msg);
    } else if (msg.type === 'error') {
      recordError('server: ' + msg.message);
    } else if (msg.type === 'roster') {
      onRoster(msg);
    } else if (msg.type === 'status') {
      if (msg.state !== 'live') clearRoom();
      if (msg.state === 'live') setStatus('live', 'watching room ' + roomName);
      else if (msg.state === 'absent') setStatus('absent', 'The room is empty: nobody is in it. Waiting for someone to join…');
      else if (msg.state === 'closed') setStatus('closed', 'The room closed: everyone left. Waiting for someone to come back…');
      else setStatus(msg.state, msg.message);
      if (msg.state === 'unauthorized' || msg.state === 'full') giveUp = msg.state === 'unauthorized';
    }
  }

  let socket = null;
  let wait = kReconnectMin;
  let giveUp = false;
  function connect() {
    const url = (location.protocol === 'https:' ? 'wss:' : 'ws:') + '//' + location.host +
      '/ws/room/' + encodeURIComponent(roomName) + (token ? '?token=' + encodeURIComponent(token) : '');
    socket = new WebSocket(url);
    socket.binaryType = 'arraybuffer';
    socket.onopen = () => {
      summary.connected = true;
      summary.connects++;
      wait = kReconnectMin;
      setVisibleState('off', '', 0, '');
      if (wantVisible) sendJson({ type: 'join', name: visibleName });
    };
    socket.onmessage = (e) => {
      if (typeof e.data === 'string') onText(e.data);
      else onFrame(e.data);
    };
    socket.onclose = () => {
      const was = summary.connected;
      summary.connected = false;
      socket = null;
      if (giveUp) return;
      clearRoom();
      setStatus('reconnecting', (was ? 'Connection to the server lost' : 'Cannot reach the server') +
        ': reconnecting…');
      const delay = wait * (0.75 + 0.5 * Math.random());
      wait = Math.min(kReconnectMax, wait * 2);
      setTimeout(() => {
        summary.reconnects++;
        connect();
      }, delay * 1000);
    };
  }

  // ------------------------------------------------------------------ visible spectator
  const visibleToggle = document.getElementById('visible');
  const visibleNote = document.getElementById('visible-note');
  function sendJson(obj) {
    if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(obj));
  }
  function setVisibleState(state, message, id, name) {
    const v = summary.visible;
    v.state = state;
    v.message = message || '';
    v.id = id || 0;
    v.name = name || '';
    if (visibleNote) visibleNote.textContent = state === 'off' ? '' : state === 'live' ?
      'visible as ' + v.name : state === 'refused' ? 'not visible: ' + v.message : state + '…';
    // Our own member stands at our camera: hidden from our own view.
    for (const m of members.values()) m.group.visible = m.id !== v.id;
  }
  function onMemberState(msg) {
    setVisibleState(msg.state, msg.message, msg.id, msg.name);
    if (msg.state === 'refused') {
      wantVisible = false;
      summary.visible.wanted = false;
      if (visibleToggle) visibleToggle.checked = false;
    }
  }
  if (visibleToggle) {
    visibleToggle.checked = wantVisible;
    visibleToggle.addEventListener('change', () => {
      wantVisible = visibleToggle.checked;
      summary.visible.wanted = wantVisible;
      sendJson(wantVisible ? { type: 'join', name: visibleName } : { type: 'leave' });
      if (!wantVisible) setVisibleState('off', '', 0, '');
    });
  }
  const viewDir = new THREE.Vector3();
  let lastPoseAt = -1;
  function sendPose() {
    const v = summary.visible;
    if (!wantVisible || (v.state !== 'joining' && v.state !== 'live')) return;
    const t = localNow();
    if (t - lastPoseAt < kPoseInterval) return;
    lastPoseAt = t;
    camera.getWorldDirection(viewDir);
    const p = camera.position;
    const clamp = (x) => Math.max(-100, Math.min(100, x));
    sendJson({ type: 'pose', x: clamp(p.x), y: clamp(p.y), z: clamp(p.z),
      yaw: Math.atan2(viewDir.x, viewDir.z), pitch: Math.asin(Math.max(-1, Math.min(1, viewDir.y))) });
    v.posesSent++;
  }

  // ------------------------------------------------------------------ playback
  const qa = new THREE.Quaternion();
  const qb = new THREE.Quaternion();
  const tmp = new THREE.Vector3();

  function pose(m, renderTime) {
    const s = m.samples;
    if (!m.loaded || s.length === 0) return;
    let a = s[0];
    let b = s[0];
    if (renderTime >= s[s.length - 1].t) {
      a = b = s[s.length - 1];  // past the newest: hold it
    } else if (renderTime > s[0].t) {
      for (let i = s.length - 1; i > 0; --i) {
        if (s[i - 1].t <= renderTime) {
          a = s[i - 1];
          b = s[i];
          break;
        }
      }
    }
    const span = b.t - a.t;
    const u = span > 1e-6 ? Math.min(1, Math.max(0, (renderTime - a.t) / span)) : 0;
    const n = Math.min(m.bones.length, a.q.length / 4, b.q.length / 4);
    let moved = 0;
    for (let j = 0; j < n; ++j) {
      qa.set(a.q[4 * j], a.q[4 * j + 1], a.q[4 * j + 2], a.q[4 * j + 3]);
      qb.set(b.q[4 * j], b.q[4 * j + 1], b.q[4 * j + 2], b.q[4 * j + 3]);
      THREE.Quaternion.slerp(qa, qb, qa, u);
      qa.normalize();
      const bone = m.bones[j];
      moved += 1 - Math.abs(bone.quaternion.dot(qa));
      bone.quaternion.copy(qa);
    }
    if (m.bones.length > 0) {
      m.bones[0].position.set(
        a.root[0] + (b.root[0] - a.root[0]) * u,
        a.root[1] + (b.root[1] - a.root[1]) * u,
        a.root[2] + (b.root[2] - a.root[2]) * u);
    }
    m.motion += moved;
  }

  function placeProps(renderTime) {
    for (const p of props.values()) {
      const s = p.samples;
      if (s.length === 0) continue;
      let a = s[s.length - 1];
      let b = a;
      for (let i = s.length - 1; i > 0; --i) {
        if (s[i - 1].t <= renderTime) {
          a = s[i - 1];
          b = s[i];
          break;
        }
      }
      const span = b.t - a.t;
      const u = span > 1e-6 ? Math.min(1, Math.max(0, (renderTime - a.t) / span)) : 0;
      p.mesh.position.copy(a.position).lerp(b.position, u);
    }
  }

  // ------------------------------------------------------------------ cameras
  let follow = null;  // member id or null
  function setCamera(value) {
    cameraSelect.value = value;
    follow = value.startsWith('follow:') ? Number(value.slice(7)) : null;
    controls.enabled = follow === null;
    summary.camera = follow === null ? 'orbit' : value;
  }
  cameraSelect.addEventListener('change', () => setCamera(cameraSelect.value));

  function updateCamera() {
    const m = follow === null ? null : members.get(follow);
    if (!m || !m.loaded) {
      controls.update();
      return;
    }
    // Behind the member's shoulder, looking where it faces (+Z of its model space).
    m.head.getWorldPosition(tmp);
    const yaw = m.seat.yaw;
    const forward = new THREE.Vector3(Math.sin(yaw), 0, Math.cos(yaw));
    const want = tmp.clone().addScaledVector(forward, -1.6).add(new THREE.Vector3(0, 0.45, 0));
    camera.position.lerp(want, 0.15);
    controls.target.lerp(tmp.clone().addScaledVector(forward, 1.5), 0.15);
    camera.lookAt(controls.target);
  }

  // ------------------------------------------------------------------ per frame
  const corner = new THREE.Vector3();
  function screenBox(m) {
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    const w = renderer.domElement.clientWidth, h = renderer.domElement.clientHeight;
    for (const bone of m.bones) {
      bone.getWorldPosition(corner);
      corner.project(camera);
      const x = (corner.x + 1) / 2 * w, y = (1 - corner.y) / 2 * h;
      x0 = Math.min(x0, x); x1 = Math.max(x1, x);
      y0 = Math.min(y0, y); y1 = Math.max(y1, y);
    }
    return { x0, y0, x1, y1 };
  }

  function updateOverlay() {
    const w = renderer.domElement.clientWidth, h = renderer.domElement.clientHeight;
    const list = [];
    for (const m of members.values()) {
      const age = Math.max(0, latestServerTime - m.joinedAt);
      m.item.textContent = m.name + ' (' + (age < 60 ? Math.floor(age) + ' s' : Math.floor(age / 60) + ' min') + ')';
      let head = null;
      if (m.loaded) {
        m.head.getWorldPosition(tmp);
        head = [tmp.x, tmp.y, tmp.z];
        tmp.y += 0.3;
        tmp.project(camera);
        const visible = m.group.visible && tmp.z < 1 && Math.abs(tmp.x) < 1.1 && Math.abs(tmp.y) < 1.1;
        m.tag.style.display = visible ? '' : 'none';
        m.tag.style.left = ((tmp.x + 1) / 2 * w) + 'px';
        m.tag.style.top = ((1 - tmp.y) / 2 * h) + 'px';
        m.screen = screenBox(m);
      } else {
        m.tag.style.display = 'none';
      }
      list.push({ id: m.id, name: m.name, avatar: m.avatar, loaded: m.loaded, failed: m.failed,
        samples: m.samples.length, motion: m.motion, head, screen: m.screen, hidden: !m.group.visible });
    }
    summary.members = list;
    summary.props = Array.from(props.values()).map((p) => ({
      id: p.id, position: [p.mesh.position.x, p.mesh.position.y, p.mesh.position.z] }));
  }

  function animate() {
    requestAnimationFrame(animate);
    const renderTime = (serverOffset === null ? 0 : localNow() + serverOffset) - kDelay;
    for (const m of members.values()) pose(m, renderTime);
    placeProps(renderTime);
    updateCamera();
    sendPose();
    renderer.render(scene, camera);
    summary.framesRendered++;
    if (summary.framesRendered % 30 === 0 && gl) {
      const e = gl.getError();
      if (e !== gl.NO_ERROR) {
        summary.webgl.glErrors++;
        recordError('WebGL error 0x' + e.toString(16));
      }
    }
    updateOverlay();
  }

  // Leaving the page closes its socket at once (a visible spectator's member goes with it),
  // even where the browser keeps the page for going back; coming back reconnects.
  window.addEventListener('pagehide', () => {
    giveUp = true;
    if (socket) socket.close(1000, 'page left');
  });
  window.addEventListener('pageshow', (e) => {
    if (!e.persisted) return;
    giveUp = false;
    if (!socket) connect();
  });
  summary.setCamera = setCamera;
  setStatus('connecting', 'connecting…');
  connect();
  animate();
})();
