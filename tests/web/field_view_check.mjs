// Drives Debian's headless Chromium through the field view while browser_test.cpp runs the
// pipeline on loopback. Each phase prints "PHASE <name> ok" on stdout, which the C++ test waits
// for before it changes the world (stops the feed, restarts the predictor); a failure prints
// "FAIL: ..." and exits 1.
//
//   node field_view_check.mjs --url http://127.0.0.1:PORT/ --out DIR --user-data-dir DIR
//                             [--chromium /usr/bin/chromium]
import { chromium } from 'playwright-core';

const argv = process.argv.slice(2);
const option = (name, fallback) => {
  const at = argv.indexOf(`--${name}`);
  return at >= 0 && at + 1 < argv.length ? argv[at + 1] : fallback;
};
const url = option('url');
const out = option('out', '.');
const userDataDir = option('user-data-dir');
const executablePath = option('chromium', '/usr/bin/chromium');
if (!url || !userDataDir) {
  console.log('FAIL: usage: field_view_check.mjs --url URL --out DIR --user-data-dir DIR');
  process.exit(2);
}

// Never outlive the test, whatever happens. The first start of Chromium on a fresh machine
// (a new profile, font caches) can take far longer than every later one, hence the margin.
const overall = setTimeout(() => {
  console.log('FAIL: overall time-out');
  process.exit(1);
}, 300_000);

const startedAt = performance.now();
const elapsed = () => `${((performance.now() - startedAt) / 1000).toFixed(1)} s`;
const phase = (name) => console.log(`PHASE ${name} ok (${elapsed()})`);
const fail = (message) => {
  throw new Error(message);
};
phase('started');

// Chromium's and playwright's own messages go to stderr, which the C++ test shows on failure:
// without them a browser that never comes up leaves nothing to read.
const logger = {
  isEnabled: (name, severity) => name === 'browser' || severity === 'error' || severity === 'warning',
  log: (name, severity, message) => console.error(`[${elapsed()} ${name} ${severity}] ${message}`),
};

let context;
let status = 0;
try {
  context = await chromium.launchPersistentContext(userDataDir, {
    executablePath,
    headless: true,
    logger,
    timeout: 180_000,
    // A laptop's screen: everything must fit without scrolling.
    viewport: { width: 1366, height: 768 },
    args: [
      '--headless', '--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--no-first-run', '--disable-quic', '--disable-extensions', '--disable-default-apps',
      '--no-default-browser-check', '--metrics-recording-only', '--disable-domain-reliability',
    ],
  });
  phase('launched');
  const page = context.pages()[0] ?? (await context.newPage());
  const pageErrors = [];
  page.on('pageerror', (error) => pageErrors.push(String(error)));
  // Nothing may leave loopback: fail on any request to another host.
  const foreign = [];
  page.on('request', (request) => {
    const host = new URL(request.url()).hostname;
    if (host !== '127.0.0.1' && !request.url().startsWith('data:')) foreign.push(request.url());
  });

  await page.goto(url, { waitUntil: 'load', timeout: 30_000 });
  phase('loaded');

  // 1. Live: the field, robots of both teams and predictions with arrows.
  await page.waitForFunction(() => Number(document.body.dataset.predictions) >= 5 &&
    document.querySelectorAll('#opponent-robots .robot').length >= 1 &&
    document.querySelectorAll('#our-robots .robot').length >= 1 &&
    document.querySelectorAll('#predictions .step').length >= 1 &&
    document.querySelectorAll('#predictions .arrow').length >= 1, null, { timeout: 20_000 });
  const live = await page.evaluate(() => {
    const field = document.getElementById('field');
    const steps = [...document.querySelectorAll('#predictions .step')];
    return {
      fieldLength: Number(field.dataset.fieldLength),
      fieldWidth: Number(field.dataset.fieldWidth),
      grid: field.dataset.grid,
      gridLines: document.querySelectorAll('#grid .grid-line').length,
      opponent: document.querySelectorAll('#opponent-robots .robot').length,
      ours: document.querySelectorAll('#our-robots .robot').length,
      steps: steps.map((s) => ({ step: Number(s.dataset.step), confidence: Number(s.dataset.confidence),
        opacity: Number(s.getAttribute('opacity')) })),
      stepItems: [...document.querySelectorAll('#steps li')].map((li) => li.textContent),
      stepLabels: [...document.querySelectorAll('#predictions .step-label')].map((t) => t.textContent),
      lastPacket: document.getElementById('status-last-packet').textContent,
      arrows: document.querySelectorAll('#predictions .arrow').length,
      centroid: document.getElementById('centroid-cell').dataset.cell,
      centroidVisible: document.getElementById('centroid-cell').getAttribute('visibility'),
      predictedCentroids: document.querySelectorAll('#predictions .predicted-centroid').length,
      latencies: window.fieldView.latenciesMs,
      received: window.fieldView.received,
      drawn: window.fieldView.drawn,
      packets: document.getElementById('status-packets').textContent,
      table: document.getElementById('status-table').textContent,
      reload: document.getElementById('status-reload').textContent,
      banner: document.getElementById('banner').hidden ? '' : document.getElementById('banner').textContent,
    };
  });
  console.log('live:', JSON.stringify({ ...live, latencies: undefined }));
  if (live.fieldLength !== 9000 || live.fieldWidth !== 6000) fail(`field ${live.fieldLength}x${live.fieldWidth}`);
  if (live.grid !== '3x2' || live.gridLines !== 3) fail(`grid ${live.grid} with ${live.gridLines} lines`);
  if (live.opponent !== 6 || live.ours !== 6) fail(`robots: ${live.opponent} opponent, ${live.ours} ours`);
  if (live.steps.length !== 2 || live.stepItems.length !== 2) fail(`steps ${JSON.stringify(live.steps)}`);
  if (!live.stepItems[0].includes('conf')) fail(`no confidence number: ${live.stepItems[0]}`);
  // Steps are labelled with their horizon in seconds: 2 s apart by default.
  if (!live.stepItems[0].startsWith('+2.0 s') || !live.stepItems[1].startsWith('+4.0 s')) {
    fail(`step items not labelled by horizon: ${JSON.stringify(live.stepItems)}`);
  }
  if (live.stepLabels.length !== 2 || !live.stepLabels.includes('+2.0 s') || !live.stepLabels.includes('+4.0 s')) {
    fail(`step labels ${JSON.stringify(live.stepLabels)}`);
  }
  // The age of the last packet is the predictor's own, never negative.
  if (!/^\d+\.\d s ago$/.test(live.lastPacket)) fail(`last packet: ${live.lastPacket}`);
  for (const s of live.steps) {
    if (!(s.opacity >= 0.3 && s.opacity <= 1)) fail(`opacity ${s.opacity} for confidence ${s.confidence}`);
  }
  if (live.centroidVisible !== 'visible' || !/^\d,\d$/.test(live.centroid)) fail(`centroid ${live.centroid}`);
  if (live.predictedCentroids !== 2) fail(`predicted centroids ${live.predictedCentroids}`);
  if (!/packets\/s/.test(live.packets) || /^0\.0 /.test(live.packets)) fail(`packets: ${live.packets}`);
  // The table the test saved: the formations it was trained on, not 0.
  if (!/transitions \/ [1-9]\d* formations/.test(live.table)) fail(`table: ${live.table}`);
  if (live.banner) fail(`unexpected banner: ${live.banner}`);
  // The page keeps up: the newest prediction that arrived is the one drawn, once its animation
  // frame comes (predictions arriving within one frame are drawn once, as the newest). How long
  // that took depends on how busy the machine is, so it is printed, not judged: a shared CI
  // machine can hold a headless frame back past 100 ms.
  const worst = Math.max(...live.latencies);
  console.log(`drawn ${live.drawn} of ${live.received} received; arrival-to-draw worst ${worst.toFixed(1)} ms`);
  if (!(live.drawn >= 1)) fail(`drew none of ${live.received} predictions received`);
  await page.waitForFunction(() => document.body.dataset.lastFrame === String(window.fieldView.prediction.frame),
    null, { timeout: 10_000 });

  // The field as SSL-Vision's client draws it: the producer's geometry packet states a 9 x 6 m
  // field with 1 m goals 180 mm deep and 2 x 1 m penalty areas. The opponent (yellow, the
  // referee says) attacks +x, so it defends the goal at -x.
  const markings = await page.evaluate(() => {
    const field = document.getElementById('field');
    const box = field.getBoundingClientRect();
    const of = (selector) => [...document.querySelectorAll(selector)].map((e) => {
      const r = e.getBoundingClientRect();
      return { ...e.dataset, cls: e.getAttribute('class'), left: r.left, right: r.right, top: r.top,
        bottom: r.bottom, boxWidth: r.width, boxHeight: r.height };
    });
    const lines = document.querySelector('#markings .field-lines').getBoundingClientRect();
    return { source: field.dataset.markings, goals: of('#goals .goal'), areas: of('#markings .penalty-area'),
      circle: Number(document.querySelector('#markings .centre-circle').getAttribute('r')),
      lines: { left: lines.left, right: lines.right, top: lines.top, bottom: lines.bottom, width: lines.width },
      svg: { left: box.left, right: box.right, top: box.top, bottom: box.bottom } };
  });
  console.log('markings:', JSON.stringify(markings));
  if (markings.source !== 'geometry') fail(`markings from ${markings.source}`);
  if (markings.goals.length !== 2 || markings.areas.length !== 2) fail(`goals/areas ${markings.goals.length}/${markings.areas.length}`);
  const mmPerPixel = 9000 / markings.lines.width;
  for (const goal of markings.goals) {
    if (goal.width !== '1000' || goal.depth !== '180') fail(`goal ${JSON.stringify(goal)}`);
    // Drawn behind its goal line, as tall as the goal is wide, and on screen.
    const behind = goal.side === '-x' ? goal.right <= markings.lines.left + 2 : goal.left >= markings.lines.right - 2;
    if (!behind) fail(`goal not behind its goal line: ${JSON.stringify(goal)}`);
    if (Math.abs(goal.boxHeight * mmPerPixel - 1000) > 60) fail(`goal ${goal.boxHeight * mmPerPixel} mm wide on screen`);
    if (goal.left < markings.svg.left || goal.right > markings.svg.right) fail('goal off the drawing');
  }
  const left = markings.goals.find((g) => g.side === '-x');
  if (left.defendedBy !== 'opponent' || !left.cls.includes('yellow')) fail(`-x goal: ${JSON.stringify(left)}`);
  const right = markings.goals.find((g) => g.side === '+x');
  if (right.defendedBy !== 'us' || !right.cls.includes('blue')) fail(`+x goal: ${JSON.stringify(right)}`);
  for (const area of markings.areas) {
    if (area.depth !== '1000' || area.width !== '2000') fail(`penalty area ${JSON.stringify(area)}`);
    if (Math.abs(area.boxHeight * mmPerPixel - 2000) > 60 || Math.abs(area.boxWidth * mmPerPixel - 1000) > 60) {
      fail(`penalty area ${area.boxWidth * mmPerPixel} x ${area.boxHeight * mmPerPixel} mm on screen`);
    }
    const against = area.side === '-x' ? Math.abs(area.left - markings.lines.left) < 3 : Math.abs(area.right - markings.lines.right) < 3;
    if (!against) fail(`penalty area not against its goal line: ${JSON.stringify(area)}`);
  }
  if (markings.circle !== 500) fail(`centre circle ${markings.circle}`);

  // The ball: where the newest message puts it, with its path.
  await page.waitForFunction(() => window.fieldView.ball && document.getElementById('ball').getAttribute('visibility') === 'visible',
    null, { timeout: 10_000 });
  const ball = await page.evaluate(() => {
    const dot = document.getElementById('ball');
    const path = document.getElementById('ball-path');
    return { x: Number(dot.dataset.x), y: Number(dot.dataset.y), cx: Number(dot.getAttribute('cx')),
      cy: Number(dot.getAttribute('cy')), message: window.fieldView.drawnBall,
      pathPoints: Number(path.dataset.points) };
  });
  console.log('ball:', JSON.stringify({ ...ball, message: undefined }));
  if (ball.x !== ball.message.x || ball.y !== ball.message.y || ball.cx !== ball.x || ball.cy !== -ball.y) {
    fail(`ball not where the message says: ${JSON.stringify(ball)}`);
  }
  if (ball.pathPoints !== ball.message.path.length) fail(`ball path ${ball.pathPoints} of ${ball.message.path.length}`);
  // On the field or its boundary area.
  if (!(Math.abs(ball.x) <= 4800 && Math.abs(ball.y) <= 3300)) fail(`ball off the field: ${ball.x}, ${ball.y}`);

  // The game's state as a banner, said once: the referee's state, the stage and the teams.
  await page.waitForFunction(() => window.fieldView.drawnStatus && window.fieldView.drawnStatus.match.heard &&
    document.getElementById('game-banner').dataset.state !== 'unknown', null, { timeout: 10_000 });
  const game = await page.evaluate(() => ({
    state: document.getElementById('game-banner').dataset.state,
    text: document.getElementById('game-state').textContent,
    detail: document.getElementById('game-detail').textContent,
    match: window.fieldView.drawnStatus.match,
    stream: document.getElementById('status').textContent,
  }));
  console.log('game:', JSON.stringify({ ...game, stream: undefined }));
  if (game.state !== game.match.game_state) fail(`banner state ${game.state} for ${game.match.game_state}`);
  if (!game.detail.includes('first half') || !game.detail.includes('ssl-formation')) fail(`banner detail: ${game.detail}`);
  if (/_/.test(game.text) || /NORMAL_/.test(game.detail)) fail(`banner in the wire's words: ${game.text} · ${game.detail}`);
  // Said once: the stage and the names are not repeated in the stream list below.
  if (game.stream.includes('first half') || game.stream.includes('NORMAL_FIRST_HALF')) fail(`stage repeated: ${game.stream}`);

  // The lately-off-by figures: all together and per phase, as the status says.
  await page.waitForFunction(() => window.fieldView.drawnStatus.live_score.length >= 1 &&
    window.fieldView.drawnStatus.live_score_by_phase.length >= 1 &&
    document.querySelectorAll('#live-score tbody tr[data-phase]').length >= 2, null, { timeout: 20_000 });
  const late = await page.evaluate(() => {
    const s = window.fieldView.drawnStatus;
    const rows = [...document.querySelectorAll('#live-score tbody tr[data-phase]')].map((tr) => ({
      phase: tr.dataset.phase, current: tr.classList.contains('current'),
      cells: [...tr.querySelectorAll('td')].map((td) => ({ model: Number(td.dataset.modelMm), stays: Number(td.dataset.persistenceMm), text: td.textContent })),
    }));
    return { rows, all: s.live_score, byPhase: s.live_score_by_phase, phase: s.match.phase,
      headers: [...document.querySelectorAll('#live-score thead th')].map((th) => th.textContent) };
  });
  console.log('lately off by:', JSON.stringify(late.rows));
  if (late.rows[0].phase !== 'all') fail('no "all" row');
  const expected = [{ phase: 'all', horizons: late.all }, ...late.byPhase];
  if (late.rows.length !== expected.length) fail(`${late.rows.length} rows for ${expected.length} phases`);
  expected.forEach((want, i) => {
    const row = late.rows[i];
    if (row.phase !== want.phase) fail(`row ${i}: ${row.phase} for ${want.phase}`);
    want.horizons.forEach((h, k) => {
      const cell = row.cells[k];
      if (cell.model !== h.model_mm || cell.stays !== h.persistence_mm) fail(`row ${row.phase}: ${JSON.stringify(cell)} for ${JSON.stringify(h)}`);
      if (cell.text !== `${Math.round(h.model_mm)} / ${Math.round(h.persistence_mm)}`) fail(`cell text ${cell.text}`);
    });
  });
  if (JSON.stringify(late.headers) !== JSON.stringify(['phase', '+2.0 s', '+4.0 s'])) fail(`headers ${late.headers}`);
  const current = late.rows.filter((r) => r.current).map((r) => r.phase);
  if (current.length > 1 || (current.length === 1 && current[0] !== late.phase)) fail(`current row ${current} in ${late.phase}`);

  // The page itself is a viewer.
  const viewers = await page.textContent('#status-clients');
  if (!/^1\b/.test(viewers)) fail(`viewers: ${viewers}`);

  // It fits a laptop's screen: no scrolling, the legend and the whole field in view, the side
  // panel whole. At 1366 x 768 and at 1280 x 720.
  const fits = async () => page.evaluate(() => {
    const inside = (id) => {
      const r = document.getElementById(id).getBoundingClientRect();
      return r.top >= 0 && r.left >= 0 && r.bottom <= innerHeight + 0.5 && r.right <= innerWidth + 0.5 && r.height > 0;
    };
    const aside = document.querySelector('aside');
    const lines = document.querySelector('#markings .field-lines').getBoundingClientRect();
    return { scroll: document.scrollingElement.scrollHeight - innerHeight,
      scrollX: document.scrollingElement.scrollWidth - innerWidth,
      legend: inside('legend'), banner: inside('game-banner'), field: inside('field'),
      aside: aside.scrollHeight - aside.clientHeight, steps: inside('steps'), clients: inside('status-clients'),
      liveScore: inside('live-score'), fieldWidth: lines.width };
  });
  for (const size of [{ width: 1366, height: 768 }, { width: 1280, height: 720 }]) {
    await page.setViewportSize(size);
    await page.waitForTimeout(300);
    const fit = await fits();
    console.log(`fit at ${size.width}x${size.height}:`, JSON.stringify(fit));
    if (fit.scroll > 0 || fit.scrollX > 0) fail(`the page scrolls at ${size.width}x${size.height}`);
    if (!fit.legend || !fit.banner || !fit.field || !fit.steps || !fit.clients || !fit.liveScore) {
      fail(`not all in view at ${size.width}x${size.height}: ${JSON.stringify(fit)}`);
    }
    if (fit.aside > 1) fail(`the side panel scrolls at ${size.width}x${size.height}`);
    if (fit.fieldWidth < 600) fail(`the field is ${fit.fieldWidth} px wide at ${size.width}x${size.height}`);
    if (size.width === 1280) await page.screenshot({ path: `${out}/field-view-1280x720.png` });
  }
  await page.setViewportSize({ width: 1366, height: 768 });
  await page.waitForTimeout(200);
  await page.screenshot({ path: `${out}/field-view.png` });
  phase('live');

  // 2. The feed stops: the page says so.
  await page.waitForFunction(() => /no vision for \d+\.\d s/.test(document.getElementById('banner').textContent) &&
    !document.getElementById('banner').hidden, null, { timeout: 15_000 });
  await page.waitForTimeout(1200);
  await page.screenshot({ path: `${out}/field-view-no-vision.png` });
  console.log('banner:', await page.textContent('#banner'));
  const stale = await page.textContent('#status-last-packet');
  if (!/^\d+\.\d s ago$/.test(stale) || parseFloat(stale) < 1) fail(`last packet without vision: ${stale}`);

  // The motion model's drawing, fed to the page as its WebSocket would (no prediction comes
  // while the feed is stopped): the last prediction with a position and radii per robot.
  const motion = await page.evaluate(async () => {
    const view = window.fieldView;
    const m = JSON.parse(JSON.stringify(view.prediction));
    m.model = 'motion';
    m.step_seconds = 0.5;
    m.steps.forEach((step, k) => {
      step.horizon_s = 0.5 * (k + 1);
      for (const robot of step.robots) {
        robot.position = [robot.centre[0] + 123, robot.centre[1] - 45];
        robot.radius_50_mm = 200 * (k + 1);
        robot.radius_90_mm = 450 * (k + 1);
      }
    });
    view.prediction = m;
    view.predictionArrivedAt = performance.now();
    // A ball rolling along a curve for the last 2 s, as a live match's would.
    const path = Array.from({ length: 30 }, (_, k) => [-2000 + 100 * k, 800 * Math.sin(k / 10)]);
    view.ball = { x: path[29][0], y: path[29][1], path };
    view.dirty = true;
    await new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve)));
    const drawnPath = document.getElementById('ball-path');
    const ballPath = {
      visible: drawnPath.getAttribute('visibility') === 'visible',
      points: drawnPath.getAttribute('points').trim().split(/\s+/).map((p) => p.split(',').map(Number)),
      length: drawnPath.getTotalLength(),
    };
    const circles = [...document.querySelectorAll('#predictions .radius-90')];
    const dots = [...document.querySelectorAll('#predictions .predicted-position')];
    return {
      robots: m.steps.reduce((n, s) => n + s.robots.length, 0),
      circles: circles.length,
      radii: circles.map((c) => Number(c.getAttribute('r'))),
      dots: dots.length,
      // Drawn where the message says, in mm (the screen's y grows downwards).
      placed: dots.every((d) => {
        const step = m.steps.find((st) => String(st.step) === d.closest('.step').dataset.step);
        const robot = step.robots.find((r) => String(r.id) === d.dataset.robotId);
        return Number(d.getAttribute('cx')) === robot.position[0] &&
          Number(d.getAttribute('cy')) === -robot.position[1];
      }),
      labels: [...document.querySelectorAll('#predictions .step-label')].map((t) => t.textContent),
      items: [...document.querySelectorAll('#steps .horizon')].map((t) => t.textContent),
      now: document.getElementById('now').textContent,
      ballPath, path,
    };
  });
  console.log('motion:', JSON.stringify({ ...motion, ballPath: undefined, path: undefined }));
  // The ball's path: every point, in mm with y turned for the screen, drawn as a line.
  if (!motion.ballPath.visible || motion.ballPath.points.length !== 30) fail(`ball path ${JSON.stringify(motion.ballPath)}`);
  motion.ballPath.points.forEach(([x, y], k) => {
    if (Math.abs(x - motion.path[k][0]) > 1e-6 || Math.abs(y + motion.path[k][1]) > 1e-6) fail(`ball path point ${k}: ${x},${y}`);
  });
  if (!(motion.ballPath.length > 2900)) fail(`ball path ${motion.ballPath.length} mm long`);
  if (motion.circles !== motion.robots || motion.dots !== motion.robots) fail(`motion circles ${JSON.stringify(motion)}`);
  if (!motion.radii.includes(450) || !motion.radii.includes(900)) fail(`90% radii ${motion.radii}`);
  if (!motion.placed) fail('predicted positions not where the message puts them');
  if (JSON.stringify(motion.items) !== JSON.stringify(['+0.5 s', '+1.0 s'])) fail(`horizons ${motion.items}`);
  if (!motion.labels.includes('+0.5 s')) fail(`labels ${motion.labels}`);
  if (!motion.now.includes('motion model')) fail(`now: ${motion.now}`);
  await page.screenshot({ path: `${out}/field-view-motion.png` });
  phase('no-vision');

  // 3. The feed restarts (its clock from the start): predictions come back, the banner goes.
  const before = await page.evaluate(() => Number(document.body.dataset.predictions));
  await page.waitForFunction((n) => Number(document.body.dataset.predictions) >= n + 3 &&
    document.getElementById('banner').hidden, before, { timeout: 20_000 });
  phase('vision-back');

  // 4. The predictor restarts: the page loses it, reconnects and draws again.
  await page.waitForFunction(() => document.body.dataset.connected === 'false', null, { timeout: 15_000 });
  console.log('banner:', await page.textContent('#banner'));
  phase('disconnected');  // the test starts the predictor again only now
  const lost = await page.evaluate(() => Number(document.body.dataset.predictions));
  await page.waitForFunction((n) => document.body.dataset.connected === 'true' &&
    Number(document.body.dataset.predictions) >= n + 3 && window.fieldView.connections >= 2, lost,
    { timeout: 20_000 });
  await page.screenshot({ path: `${out}/field-view-reconnected.png` });
  phase('reconnected');

  if (pageErrors.length) fail(`page errors: ${pageErrors.join('; ')}`);
  if (foreign.length) fail(`requests off loopback: ${foreign.join(', ')}`);
  console.log('PASS');
} catch (error) {
  console.log(`FAIL: ${error.message}`);
  status = 1;
} finally {
  if (context) await context.close().catch(() => {});
  clearTimeout(overall);
}
process.exit(status);
