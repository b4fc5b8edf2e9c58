// The live field view: receives the predictor's JSON messages over a WebSocket and redraws the
// field in the next animation frame. Everything is drawn as SVG with ids and data attributes,
// so that a test (or a curious user) can read what is on screen from the DOM.
'use strict';

(() => {
  const SVG_NS = 'http://www.w3.org/2000/svg';
  const MARGIN_MM = 300;
  const ROBOT_RADIUS_MM = 90;
  const NO_VISION_AFTER_S = 1.0;   // the banner shows when no packet arrived for longer
  const STALE_CONNECTION_MS = 3000; // no message at all for this long: reconnect
  const STEP_COLOURS = ['#ff4d6d', '#c77dff', '#4cc9f0', '#80ed99', '#ffb703'];

  const view = {
    setup: null,
    prediction: null,
    predictionArrivedAt: 0,
    status: null,
    statusArrivedAt: 0,
    lastMessageAt: 0,
    connected: false,
    reconnectDelayMs: 250,
    connections: 0,
    received: 0,
    drawn: 0,
    lastDrawnArrival: -1,
    latenciesMs: [],  // arrival to drawn, per prediction (the last 200)
    dirty: true,
    setupKey: '',
  };
  window.fieldView = view;  // for tests and the console

  const $ = (id) => document.getElementById(id);
  const svgElement = (name, attributes, parent) => {
    const element = document.createElementNS(SVG_NS, name);
    for (const [key, value] of Object.entries(attributes)) element.setAttribute(key, value);
    if (parent) parent.appendChild(element);
    return element;
  };
  const fmt = (value, digits) => (value === null || value === undefined || !Number.isFinite(value))
    ? '–' : value.toFixed(digits);
  const confidenceText = (c) => (c >= 0.01 ? c.toFixed(3) : c.toExponential(2));
  // Opacity from confidence: 0.3 + 0.7 * sqrt(confidence), so that the small confidences of later
  // steps (a product of probabilities) stay visible while a sure step is fully opaque.
  const opacityOf = (confidence) => 0.3 + 0.7 * Math.sqrt(Math.max(0, Math.min(1, confidence)));
  // How far ahead a step is, in seconds ("+2.0 s", "+0.25 s"): one decimal unless the horizon
  // needs more. From a predictor that sends no horizon_s, step x step_seconds.
  const horizonOf = (prediction, step) => (Number.isFinite(step.horizon_s)
    ? step.horizon_s : step.step * prediction.step_seconds);
  const horizonText = (seconds) => {
    if (!Number.isFinite(seconds)) return '+?';
    let digits = 1;
    while (digits < 3 && Math.abs(Number(seconds.toFixed(digits)) - seconds) > 1e-9) digits += 1;
    return `+${seconds.toFixed(digits)} s`;
  };

  // The field's y grows upwards, the screen's downwards.
  const sx = (x) => x;
  const sy = (y) => -y;

  function connect() {
    const scheme = location.protocol === 'https:' ? 'wss://' : 'ws://';
    let ws;
    try {
      ws = new WebSocket(scheme + location.host + '/ws');
    } catch (error) {
      scheduleReconnect();
      return;
    }
    view.ws = ws;
    ws.onopen = () => {
      view.connected = true;
      view.connections += 1;
      view.reconnectDelayMs = 250;
      view.lastMessageAt = performance.now();
      view.dirty = true;
    };
    ws.onmessage = (event) => {
      const arrived = performance.now();
      view.lastMessageAt = arrived;
      let message;
      try {
        message = JSON.parse(event.data);
      } catch (error) {
        return;
      }
      if (message.type === 'prediction') {
        view.prediction = message;
        view.predictionArrivedAt = arrived;
        view.received += 1;
      } else if (message.type === 'status') {
        view.status = message;
        view.statusArrivedAt = arrived;
      } else {
        return;
      }
      view.setup = {
        field: message.field, grid: message.grid, opponent_color: message.opponent_color,
        our_color: message.our_color, opponent_attacks: message.opponent_attacks,
      };
      view.dirty = true;
    };
    ws.onclose = () => {
      if (view.ws !== ws) return;
      view.ws = null;
      view.connected = false;
      view.dirty = true;
      scheduleReconnect();
    };
    ws.onerror = () => ws.close();
  }

  function scheduleReconnect() {
    setTimeout(connect, view.reconnectDelayMs);
    view.reconnectDelayMs = Math.min(2000, view.reconnectDelayMs * 2);
  }

  // Drawing -------------------------------------------------------------------------------

  function cellCentre(setup, cx, cy) {
    const L = setup.field.length, W = setup.field.width;
    const x = (cx + 0.5) * L / setup.grid.length - L / 2;
    const y = (cy + 0.5) * W / setup.grid.width - W / 2;
    return setup.opponent_attacks === '-x' ? [-x, -y] : [x, y];
  }

  function drawSetup(setup) {
    const key = JSON.stringify(setup);
    if (key === view.setupKey) return;
    view.setupKey = key;
    const L = setup.field.length, W = setup.field.width;
    const field = $('field');
    field.setAttribute('viewBox', `${-L / 2 - MARGIN_MM} ${-W / 2 - MARGIN_MM} ${L + 2 * MARGIN_MM} ${W + 2 * MARGIN_MM}`);
    field.dataset.fieldLength = L;
    field.dataset.fieldWidth = W;
    field.dataset.grid = `${setup.grid.length}x${setup.grid.width}`;
    const surface = $('surface');
    surface.setAttribute('x', -L / 2 - MARGIN_MM);
    surface.setAttribute('y', -W / 2 - MARGIN_MM);
    surface.setAttribute('width', L + 2 * MARGIN_MM);
    surface.setAttribute('height', W + 2 * MARGIN_MM);

    const markings = $('markings');
    markings.replaceChildren();
    svgElement('rect', { class: 'marking', x: -L / 2, y: -W / 2, width: L, height: W }, markings);
    svgElement('line', { class: 'marking', x1: 0, y1: -W / 2, x2: 0, y2: W / 2 }, markings);
    svgElement('circle', { class: 'marking', cx: 0, cy: 0, r: 500 }, markings);

    const grid = $('grid');
    grid.replaceChildren();
    for (let i = 1; i < setup.grid.length; i++) {
      const x = -L / 2 + i * L / setup.grid.length;
      svgElement('line', { class: 'grid-line', x1: x, y1: -W / 2, x2: x, y2: W / 2 }, grid);
    }
    for (let j = 1; j < setup.grid.width; j++) {
      const y = -W / 2 + j * W / setup.grid.width;
      svgElement('line', { class: 'grid-line', x1: -L / 2, y1: y, x2: L / 2, y2: y }, grid);
    }
    const cellW = L / setup.grid.length, cellH = W / setup.grid.width;
    for (let cx = 0; cx < setup.grid.length; cx++) {
      for (let cy = 0; cy < setup.grid.width; cy++) {
        const [x, y] = cellCentre(setup, cx, cy);
        const label = svgElement('text', {
          class: 'cell-label', x: sx(x) - cellW / 2 + 60, y: sy(y) - cellH / 2 + 190,
        }, grid);
        label.textContent = `(${cx},${cy})`;
      }
    }
    const attack = $('attack-label');
    attack.setAttribute('x', -L / 2);
    attack.setAttribute('y', -W / 2 - 80);
    attack.textContent = `opponent (${setup.opponent_color}) attacks ${setup.opponent_attacks === '-x' ? '←' : '→'}`;
  }

  function drawRobots(groupId, robots, kind, colour) {
    const group = $(groupId);
    group.replaceChildren();
    for (const robot of robots) {
      const g = svgElement('g', {
        class: `robot ${kind} ${colour}`, 'data-robot-id': robot.id,
        transform: `translate(${sx(robot.x)} ${sy(robot.y)})`,
      }, group);
      svgElement('circle', { r: ROBOT_RADIUS_MM }, g);
      svgElement('text', {}, g).textContent = robot.id;
    }
    group.dataset.count = robots.length;
  }

  function stepMarker(index, colour) {
    const id = `arrowhead-${index}`;
    if (!document.getElementById(id)) {
      const defs = $('field').querySelector('defs');
      const marker = svgElement('marker', {
        id, viewBox: '0 0 10 10', refX: 8, refY: 5, markerWidth: 5, markerHeight: 5,
        orient: 'auto-start-reverse', markerUnits: 'strokeWidth',
      }, defs);
      svgElement('path', { d: 'M0,0 L10,5 L0,10 z', fill: colour }, marker);
    }
    return `url(#${id})`;
  }

  function drawPrediction(setup, prediction) {
    const cellW = setup.field.length / setup.grid.length;
    const cellH = setup.field.width / setup.grid.width;
    const centroid = $('centroid-cell');
    if (prediction.centroid && prediction.centroid.centre) {
      const [x, y] = prediction.centroid.centre;
      centroid.setAttribute('x', sx(x) - cellW / 2);
      centroid.setAttribute('y', sy(y) - cellH / 2);
      centroid.setAttribute('width', cellW);
      centroid.setAttribute('height', cellH);
      centroid.setAttribute('visibility', 'visible');
      centroid.dataset.cell = prediction.centroid.cell.join(',');
    } else {
      centroid.setAttribute('visibility', 'hidden');
    }

    const group = $('predictions');
    group.replaceChildren();
    // Where each robot is before each step: as seen for step 1, then where the previous step put
    // it (its predicted position for the motion model, its cell's centre for the paper's).
    let from = new Map(prediction.opponent.map((r) => [r.id, [r.x, r.y]]));
    const steps = prediction.steps || [];
    const layers = [];
    steps.forEach((step, index) => {
      const colour = STEP_COLOURS[index % STEP_COLOURS.length];
      const g = svgElement('g', {
        class: 'step', id: `step-${step.step}`, 'data-step': step.step,
        'data-horizon-s': horizonOf(prediction, step),
        'data-confidence': step.confidence, opacity: opacityOf(step.confidence).toFixed(3),
      });
      layers.push(g);
      if (step.centroid && step.centroid.centre) {
        const [x, y] = step.centroid.centre;
        const inset = 40 + 70 * index;  // nested when several steps share a cell
        svgElement('rect', {
          class: 'predicted-centroid', stroke: colour, 'data-cell': step.centroid.cell.join(','),
          x: sx(x) - cellW / 2 + inset, y: sy(y) - cellH / 2 + inset,
          width: Math.max(0, cellW - 2 * inset), height: Math.max(0, cellH - 2 * inset),
        }, g);
        const label = svgElement('text', {
          class: 'step-label', fill: colour,
          x: sx(x) - cellW / 2 + inset + 60 + 650 * index, y: sy(y) + cellH / 2 - inset - 60,
        }, g);
        label.textContent = horizonText(horizonOf(prediction, step));
      }
      const next = new Map();
      for (const robot of step.robots) {
        const stated = Array.isArray(robot.position) && Number.isFinite(robot.radius_90_mm);
        const [tx, ty] = stated ? robot.position : robot.centre;
        next.set(robot.id, [tx, ty]);
        if (stated) {
          // The motion model: its predicted position and the circle holding the robot with 90%
          // probability, both in millimetres on the field.
          svgElement('circle', {
            class: 'radius-90', stroke: colour, fill: colour, 'data-robot-id': robot.id,
            'data-radius-90': robot.radius_90_mm, 'data-radius-50': robot.radius_50_mm,
            cx: sx(tx), cy: sy(ty), r: Math.max(0, robot.radius_90_mm),
          }, g);
          svgElement('circle', {
            class: 'predicted-position', fill: colour, 'data-robot-id': robot.id,
            'data-x': tx, 'data-y': ty, cx: sx(tx), cy: sy(ty), r: 45,
          }, g);
        } else {
          svgElement('circle', {
            class: 'predicted-cell', stroke: colour, 'data-robot-id': robot.id,
            cx: sx(tx), cy: sy(ty), r: 60 + 25 * index,
          }, g);
        }
        const start = from.get(robot.id);
        if (!start) continue;
        const [fx, fy] = start;
        const dx = tx - fx, dy = ty - fy;
        const length = Math.hypot(dx, dy);
        if (length < 1) continue;  // holds its place: the ring alone shows it
        // Start at the robot's edge, not its centre.
        const trim = index === 0 ? Math.min(ROBOT_RADIUS_MM, length / 2) : 0;
        svgElement('line', {
          class: 'arrow', stroke: colour, 'data-robot-id': robot.id, 'marker-end': stepMarker(index, colour),
          x1: sx(fx + dx * trim / length), y1: sy(fy + dy * trim / length), x2: sx(tx), y2: sy(ty),
        }, g);
      }
      from = next;
    });
    // Step 1 on top.
    for (const layer of layers.reverse()) group.appendChild(layer);
    group.dataset.steps = steps.length;
  }

  function drawSidePanel(setup, prediction) {
    if (prediction) {
      const c = prediction.centroid.cell;
      $('now').textContent = `t=${fmt(prediction.t, 2)} s · frame ${prediction.frame} · centroid C(${c[0]},${c[1]}) · ` +
        `${prediction.opponent.length} opponent, ${prediction.ours.length} ours · ${prediction.model || 'paper'} model`;
    }
    const list = $('steps');
    list.replaceChildren();
    for (const [index, step] of (prediction ? prediction.steps : []).entries()) {
      const item = document.createElement('li');
      item.dataset.step = step.step;
      const colour = STEP_COLOURS[index % STEP_COLOURS.length];
      const name = document.createElement('span');
      name.className = 'horizon';
      name.textContent = horizonText(horizonOf(prediction, step));
      name.style.color = colour;
      const what = document.createElement('span');
      const cell = step.centroid.cell;
      what.textContent = `C(${cell[0]},${cell[1]}) p=${fmt(step.centroid_p, 3)}${step.centroid_unseen ? ' unseen' : ''}`;
      const conf = document.createElement('span');
      conf.className = 'conf';
      conf.textContent = `conf ${confidenceText(step.confidence)}`;
      const bar = document.createElement('div');
      bar.className = 'bar';
      const fill = document.createElement('span');
      fill.style.width = `${(100 * Math.max(0, Math.min(1, step.confidence))).toFixed(1)}%`;
      fill.style.background = colour;
      bar.appendChild(fill);
      item.append(name, what, conf, bar);
      list.appendChild(item);
    }
  }

  // Seconds since the predictor last received a packet: the age the server measured on its own
  // clock when it wrote the status, plus how long that status has been here on this page's
  // monotonic clock. Neither the data's t_capture (the simulator's or camera's seconds) nor the
  // two machines' wall clocks are compared, so it is never negative.
  function sinceVision() {
    const s = view.status;
    if (!s || s.since_packet_s === null || s.since_packet_s === undefined) return null;
    const here = Math.max(0, performance.now() - view.statusArrivedAt) / 1000;
    return Math.max(0, s.since_packet_s) + here;
  }

  function drawStatus() {
    const s = view.status;
    const banner = $('banner');
    let text = '';
    let kind = '';
    const since = sinceVision();
    if (!view.connected) {
      text = view.connections ? 'lost the predictor: reconnecting…' : 'connecting to the predictor…';
      kind = 'bad';
    } else if (s && since === null) {
      text = 'no vision yet: is the vision feed running?';
    } else if (since !== null && since > NO_VISION_AFTER_S) {
      text = `no vision for ${since.toFixed(1)} s`;
    } else if (s && !s.table.loaded) {
      text = 'waiting for the table: start ssl-trainer';
      kind = 'info';
    }
    banner.hidden = !text;
    banner.textContent = text;
    banner.className = kind;
    banner.dataset.kind = text ? (kind || 'warn') : '';
    document.body.dataset.connected = view.connected;
    document.body.dataset.vision = since !== null && since <= NO_VISION_AFTER_S ? 'live' : 'stale';
    $('connection').textContent = view.connected ? 'live' : 'disconnected';
    if (!s) return;
    if (s.match) {
      $('status-opponent').textContent = s.match.opponent;
      $('status-game').textContent = s.match.referee === 'no referee heard'
        ? 'no referee heard' : `${s.match.game_state.replace(/_/g, ' ')} · ${s.match.referee}`;
    }
    if (Array.isArray(s.live_score)) {
      // How far the predictions lately were, against everyone staying where they were.
      $('status-live-score').textContent = s.live_score.length ?
          s.live_score
              .map(
                  (h) => `${fmt(h.horizon_s, 1)} s ahead: ${Math.round(h.model_mm)} mm ` +
                      `(everyone stays: ${Math.round(h.persistence_mm)} mm)`)
              .join(' · ') :
          'nothing checked yet';
    }
    $('status-packets').textContent = `${fmt(s.packets_per_s, 1)} packets/s (${s.packets} in all)`;
    $('status-last-packet').textContent = since === null ? 'never' : `${since.toFixed(1)} s ago`;
    $('status-parse-errors').textContent = `${s.parse_errors}` + (s.kernel_drops ? ` · ${s.kernel_drops} kernel drops` : '');
    $('status-table').textContent = s.table.loaded
      ? `${s.table.transitions} transitions / ${s.table.formations} formations · ${s.table.states_seen} states` +
        (Number.isFinite(s.table.motion_instances) ? ` · ${s.table.motion_instances} motion instances` : '')
      : 'not loaded yet';
    if (s.table.loaded_unix_ms !== null) {
      const at = new Date(s.table.loaded_unix_ms);
      const ago = Math.max(0, (Date.now() - s.table.loaded_unix_ms) / 1000);
      $('status-reload').textContent = `${at.toLocaleTimeString()} (${ago.toFixed(1)} s ago, ${s.table.reloads} loads)`;
    } else {
      $('status-reload').textContent = s.table.error || 'never';
    }
    $('status-predictions').textContent = `${s.predictions} from ${s.formations} formations`;
    $('status-clients').textContent = `${s.clients}` + (s.dropped_frames ? ` · ${s.dropped_frames} frames dropped for slow viewers` : '');
  }

  function render(now) {
    const setup = view.setup;
    if (setup) drawSetup(setup);
    const prediction = view.prediction;
    if (setup && prediction && view.predictionArrivedAt !== view.lastDrawnArrival) {
      drawPrediction(setup, prediction);
      drawRobots('opponent-robots', prediction.opponent, 'opponent', setup.opponent_color);
      drawSidePanel(setup, prediction);
      view.lastDrawnArrival = view.predictionArrivedAt;
      view.drawn += 1;
      view.latenciesMs.push(performance.now() - view.predictionArrivedAt);
      if (view.latenciesMs.length > 200) view.latenciesMs.shift();
      document.body.dataset.predictions = view.drawn;
      document.body.dataset.lastFrame = prediction.frame;
    }
    // Ours: from the newest message that carries them (statuses come even without a table).
    const ours = (view.status && view.statusArrivedAt > view.predictionArrivedAt) || !prediction
      ? (view.status ? view.status.ours : [])
      : prediction.ours;
    if (setup) drawRobots('our-robots', ours || [], 'ours', setup.our_color);
    drawStatus();
  }

  function frame(now) {
    if (view.dirty) {
      view.dirty = false;
      render(now);
    }
    requestAnimationFrame(frame);
  }

  // The banner's clock and a stale connection are checked ten times a second.
  setInterval(() => {
    const now = performance.now();
    if (view.ws && view.connected && now - view.lastMessageAt > STALE_CONNECTION_MS) {
      const stale = view.ws;
      view.ws = null;  // its onclose, whenever it comes, is ignored
      view.connected = false;
      stale.close();
      scheduleReconnect();
    }
    view.dirty = true;
  }, 100);

  connect();
  requestAnimationFrame(frame);
})();
