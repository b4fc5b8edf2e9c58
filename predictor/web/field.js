// The live field view: receives the predictor's JSON messages over a WebSocket and redraws the
// field in the next animation frame. Everything is drawn as SVG with ids and data attributes,
// so that a test (or a curious user) can read what is on screen from the DOM.
'use strict';

(() => {
  const SVG_NS = 'http://www.w3.org/2000/svg';
  const MARGIN_MM = 60;             // beyond the boundary area, so its edge shows
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
    ball: null,
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
      // The ball, from the newest message that says where it is (or that it is not seen).
      if ('ball' in message) {
        view.ball = message.ball;
      }
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

  // The field as SSL-Vision's own client draws it: the boundary area, the field lines, the centre
  // circle and mark, both penalty areas and both goals, each goal in the colour of the team that
  // defends it. Sizes from the feed's geometry packet, else the rules' (field.markings.source).
  function drawSetup(setup) {
    const key = JSON.stringify(setup);
    if (key === view.setupKey) return;
    view.setupKey = key;
    const L = setup.field.length, W = setup.field.width;
    const m = setup.field.markings;  // the predictor always sends them (field_markings.hpp)
    const outside = Math.max(m.boundary_width, m.goal_depth + 40);
    const margin = outside + MARGIN_MM;
    const field = $('field');
    field.setAttribute('viewBox', `${-L / 2 - margin} ${-W / 2 - margin} ${L + 2 * margin} ${W + 2 * margin}`);
    field.dataset.fieldLength = L;
    field.dataset.fieldWidth = W;
    field.dataset.grid = `${setup.grid.length}x${setup.grid.width}`;
    field.dataset.markings = m.source;
    const rect = (element, x, y, width, height) => {
      element.setAttribute('x', x);
      element.setAttribute('y', y);
      element.setAttribute('width', width);
      element.setAttribute('height', height);
    };
    rect($('surface'), -L / 2 - outside, -W / 2 - outside, L + 2 * outside, W + 2 * outside);
    rect($('playing-area'), -L / 2, -W / 2, L, W);

    const markings = $('markings');
    markings.replaceChildren();
    svgElement('rect', { class: 'marking field-lines', x: -L / 2, y: -W / 2, width: L, height: W }, markings);
    svgElement('line', { class: 'marking halfway-line', x1: 0, y1: -W / 2, x2: 0, y2: W / 2 }, markings);
    svgElement('circle', { class: 'marking centre-circle', cx: 0, cy: 0, r: m.center_circle_radius }, markings);
    svgElement('circle', { class: 'centre-mark', cx: 0, cy: 0, r: 40 }, markings);
    // Which end each team defends: the opponent attacks towards +x or -x.
    const opponentDefendsNegative = setup.opponent_attacks !== '-x';
    const goals = $('goals');
    goals.replaceChildren();
    for (const side of [-1, 1]) {
      const goalLine = side * L / 2;
      const defender = (side < 0) === opponentDefendsNegative ? 'opponent' : 'us';
      const colour = defender === 'opponent' ? setup.opponent_color : setup.our_color;
      const depth = m.penalty_area_depth, half = m.penalty_area_width / 2;
      svgElement('rect', {
        class: 'marking penalty-area', 'data-side': side < 0 ? '-x' : '+x', 'data-defended-by': defender,
        'data-depth': depth, 'data-width': m.penalty_area_width,
        x: side < 0 ? -L / 2 : L / 2 - depth, y: -half, width: depth, height: 2 * half,
      }, markings);
      // The goal: its two side walls and back wall behind the goal line.
      const back = goalLine + side * m.goal_depth;
      const g = m.goal_width / 2;
      svgElement('path', {
        class: `goal ${colour}`, 'data-side': side < 0 ? '-x' : '+x', 'data-defended-by': defender,
        'data-width': m.goal_width, 'data-depth': m.goal_depth,
        d: `M${goalLine},${-g} L${back},${-g} L${back},${g} L${goalLine},${g}`,
      }, goals);
    }

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

  // The ball where the follower last saw it, and its path over the last seconds.
  function drawBall(ball) {
    view.drawnBall = ball;  // what the page shows, for tests and the console
    const dot = $('ball');
    const path = $('ball-path');
    if (!ball) {
      dot.setAttribute('visibility', 'hidden');
      path.setAttribute('visibility', 'hidden');
      delete dot.dataset.x;
      delete dot.dataset.y;
      path.dataset.points = 0;
      return;
    }
    dot.setAttribute('cx', sx(ball.x));
    dot.setAttribute('cy', sy(ball.y));
    dot.setAttribute('visibility', 'visible');
    dot.dataset.x = ball.x;
    dot.dataset.y = ball.y;
    const points = ball.path || [];
    path.setAttribute('points', points.map(([x, y]) => `${sx(x)},${sy(y)}`).join(' '));
    path.setAttribute('visibility', points.length >= 2 ? 'visible' : 'hidden');
    path.dataset.points = points.length;
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

  // The game's state as a banner: what the referee's last command says, whose restart it is, the
  // stage and the teams.
  const STATE_WORDS = {
    halt: 'halt', stop: 'stop', running: 'running', free_kick: 'free kick',
    kickoff_preparation: 'kick-off', penalty_preparation: 'penalty', ball_placement: 'ball placement',
    timeout: 'timeout',
  };
  const stageText = (stage) => {
    const known = {
      NORMAL_FIRST_HALF_PRE: 'before the first half', NORMAL_FIRST_HALF: 'first half',
      NORMAL_HALF_TIME: 'half time', NORMAL_SECOND_HALF_PRE: 'before the second half',
      NORMAL_SECOND_HALF: 'second half', EXTRA_TIME_BREAK: 'break before extra time',
      EXTRA_FIRST_HALF_PRE: 'before extra time', EXTRA_FIRST_HALF: 'extra time, first half',
      EXTRA_HALF_TIME: 'extra time, half time', EXTRA_SECOND_HALF_PRE: 'before extra time\'s second half',
      EXTRA_SECOND_HALF: 'extra time, second half', PENALTY_SHOOTOUT_BREAK: 'break before the shoot-out',
      PENALTY_SHOOTOUT: 'penalty shoot-out', POST_GAME: 'after the game',
    };
    return known[stage] || String(stage).toLowerCase().replace(/_/g, ' ');
  };
  function drawGameBanner(match, opponentColour) {
    const banner = $('game-banner');
    let state;
    let detail;
    if (!match.heard) {
      state = 'no referee';
      detail = 'every moment counts as running play';
    } else {
      const words = STATE_WORDS[match.game_state] || match.game_state.replace(/_/g, ' ');
      const whose = match.for_team === 'opponent' ? `their ${words} (${opponentColour})`
        : match.for_team === 'us' ? `our ${words}` : words;
      state = whose;
      const parts = [];
      if (match.stage) parts.push(stageText(match.stage));
      if (match.yellow || match.blue) parts.push(`yellow ${match.yellow || '?'} v blue ${match.blue || '?'}`);
      detail = parts.join(' · ');
    }
    $('game-state').textContent = state;
    $('game-detail').textContent = detail;
    $('game-detail').title = detail;
    banner.dataset.state = match.heard ? match.game_state : 'unknown';
    banner.dataset.forTeam = match.for_team || '';
    banner.dataset.opponentColor = opponentColour || '';
    banner.dataset.phase = match.phase || '';
    const target = $('placement-target');
    if (match.heard && match.game_state === 'ball_placement' && Array.isArray(match.designated_position)) {
      const [x, y] = match.designated_position;
      target.setAttribute('cx', sx(x));
      target.setAttribute('cy', sy(y));
      target.setAttribute('visibility', 'visible');
    } else {
      target.setAttribute('visibility', 'hidden');
    }
  }

  // How far the predictions lately were, against everyone staying where they were: all together
  // and by the game's phase when they were made, the current phase's row marked.
  const PHASE_WORDS = {
    running: 'running', stop: 'stop', halt: 'halt', ball_placement_opponent: 'their placement',
    ball_placement_us: 'our placement', kickoff_opponent: 'their kick-off', kickoff_us: 'our kick-off',
    free_kick_opponent: 'their free kick', free_kick_us: 'our free kick', penalty: 'penalty',
  };
  function drawLiveScore(s) {
    // Redrawn only for a new status, so that a row's tooltip stays while it is read.
    if (!Array.isArray(s.live_score) || view.drawnStatus === s) return;
    view.drawnStatus = s;  // the status the table and the banner show
    const table = $('live-score');
    const rows = [{ phase: 'all', horizons: s.live_score }].concat(s.live_score_by_phase || []);
    const horizons = [...new Set(s.live_score.map((h) => h.horizon_s))];
    const head = document.createElement('tr');
    head.appendChild(Object.assign(document.createElement('th'), { textContent: 'phase' }));
    for (const h of horizons) {
      head.appendChild(Object.assign(document.createElement('th'), { textContent: horizonText(h) }));
    }
    table.tHead.replaceChildren(head);
    const body = table.tBodies[0];
    if (!s.live_score.length) {
      const tr = document.createElement('tr');
      tr.appendChild(Object.assign(document.createElement('td'), { className: 'none', textContent: 'nothing checked yet' }));
      body.replaceChildren(tr);
      return;
    }
    const current = s.match ? s.match.phase : '';
    body.replaceChildren(...rows.map((row) => {
      const tr = document.createElement('tr');
      tr.dataset.phase = row.phase;
      if (row.phase === current) tr.className = 'current';
      tr.appendChild(Object.assign(document.createElement('th'), {
        textContent: row.phase === 'all' ? 'all' : (PHASE_WORDS[row.phase] || row.phase),
      }));
      for (const h of horizons) {
        const td = document.createElement('td');
        const figure = row.horizons.find((x) => x.horizon_s === h);
        if (figure) {
          td.dataset.modelMm = figure.model_mm;
          td.dataset.persistenceMm = figure.persistence_mm;
          // Within a millimetre is a tie (a halt's zeros), neither better nor worse.
          const margin = figure.persistence_mm - figure.model_mm;
          td.className = Math.abs(margin) < 1 ? 'tie' : margin > 0 ? 'better' : 'worse';
          td.title = `${Math.round(figure.robots)} robots lately (faded)`;
          td.append(Object.assign(document.createElement('span'), { className: 'model', textContent: Math.round(figure.model_mm) }),
            Object.assign(document.createElement('span'), { className: 'vs', textContent: ` / ${Math.round(figure.persistence_mm)}` }));
        } else {
          td.textContent = '–';
        }
        tr.appendChild(td);
      }
      return tr;
    }));
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
      drawGameBanner(s.match, s.opponent_color);
    }
    drawLiveScore(s);
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
    drawBall(view.ball);
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
