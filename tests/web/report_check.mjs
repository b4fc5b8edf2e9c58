// Opens ssl-evaluate's --report page in Debian's headless Chromium (file://, offline) and checks
// that every figure is drawn and that the numbers are the CSV's. Prints "PHASE <name> ok" per
// step and "RENDER <ms>" (navigation start to the load event); a failure prints "FAIL: ..." and
// exits 1.
//
//   node report_check.mjs --report PAGE.html --csv ACCURACY.csv --user-data-dir DIR
//                         [--chromium /usr/bin/chromium] [--screenshot FILE.png]
import { readFileSync } from 'node:fs';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

const argv = process.argv.slice(2);
const option = (name, fallback) => {
  const at = argv.indexOf(`--${name}`);
  return at >= 0 && at + 1 < argv.length ? argv[at + 1] : fallback;
};
const report = option('report');
const csvPath = option('csv');
const userDataDir = option('user-data-dir');
const executablePath = option('chromium', '/usr/bin/chromium');
const screenshot = option('screenshot');
if (!report || !csvPath || !userDataDir) {
  console.log('FAIL: usage: report_check.mjs --report PAGE --csv CSV --user-data-dir DIR');
  process.exit(2);
}
const overall = setTimeout(() => {
  console.log('FAIL: overall time-out');
  process.exit(1);
}, 240_000);
const fail = (message) => {
  throw new Error(message);
};

// The accuracy CSV, keyed as the page's cells are: game state, horizon and method. The report
// draws the last section (holdout's chains come after its horizons), so a later row wins.
const lines = readFileSync(csvPath, 'utf8').trim().split('\n');
const header = lines[0].split(',');
const column = (name) => header.indexOf(name);
const expected = new Map();
for (const line of lines.slice(1)) {
  const f = line.split(',');
  expected.set(`${f[column('game_state')]}|${f[column('horizon_s')]}|${f[column('method')]}`,
               f[column('mean_error_mm')]);
}

let context;
let status = 0;
try {
  context = await chromium.launchPersistentContext(userDataDir, {
    executablePath, headless: true, timeout: 180_000, viewport: { width: 1280, height: 800 },
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--no-first-run', '--disable-extensions', '--disable-default-apps'],
  });
  console.log('PHASE launched ok');
  const page = context.pages()[0] ?? (await context.newPage());
  // Offline: any request beyond the file itself fails the test.
  const requests = [];
  page.on('request', (request) => {
    if (!request.url().startsWith('file://')) requests.push(request.url());
  });
  await page.goto(pathToFileURL(report).href, { waitUntil: 'load', timeout: 30_000 });
  const render = await page.evaluate(() => {
    const [navigation] = performance.getEntriesByType('navigation');
    return navigation.loadEventEnd - navigation.startTime;
  });
  console.log(`RENDER ${render.toFixed(0)}`);
  if (requests.length) fail(`the page asked the network for ${requests.join(', ')}`);
  if ((await page.locator('script').count()) !== 0) fail('the page has a script');
  phase('loaded');

  // The table by game state: every mean is the CSV's, to the last digit.
  const cells = await page.$$eval('#by-state td.mean', (tds) => tds.map((td) => ({
    state: td.parentElement.dataset.state, horizon: td.parentElement.dataset.horizon,
    method: td.dataset.method, value: td.dataset.value,
    interval: td.querySelector('.ci') !== null,
  })));
  if (cells.length === 0) fail('no means in the table by game state');
  for (const cell of cells) {
    const want = expected.get(`${cell.state}|${cell.horizon}|${cell.method}`);
    if (want === undefined) fail(`no CSV row for ${cell.state} ${cell.horizon} ${cell.method}`);
    if (want !== cell.value) fail(`${cell.state} ${cell.horizon} ${cell.method}: page ${cell.value}, CSV ${want}`);
  }
  const withIntervals = cells.filter((cell) => cell.interval).length;
  console.log(`TABLE ${cells.length} means, ${withIntervals} with intervals`);
  if (withIntervals === 0) fail('no interval in the table');
  phase('table');

  // Every figure drawn, and drawn with something in it.
  const count = (selector) => page.locator(selector).count();
  const methods = await page.$$eval('#by-state thead th', (ths) => ths.length - 5);
  const methodLines = await count("#error-by-horizon polyline.method");
  if (methodLines !== methods) fail(`error against horizon: ${methodLines} lines for ${methods} methods`);
  const points = await page.$$eval('#error-by-horizon polyline.method',
                                   (ps) => ps.map((p) => p.getAttribute('points').trim().split(' ').length));
  if (points.some((n) => n < 2)) fail('a method line with fewer than two points');
  const diagrams = await count('#reliability svg');
  const bins = await count('#reliability circle.bin');
  if (diagrams < 2 || bins < diagrams) fail(`reliability: ${diagrams} diagrams, ${bins} bins`);
  const radii = await count('#radii tbody tr');
  if (radii === 0) fail('no radii coverage rows');
  const bars = await count('#robot-errors rect.bar');
  if (bars < methods) fail(`per robot id: ${bars} bars`);
  const heat = await count('#heat-map rect.cell');
  if (heat === 0) fail('the heat map has no cell');
  // Laid out: each figure has a size on the page.
  for (const id of ['#error-by-horizon', '#robot-errors', '#heat-map']) {
    const box = await page.locator(id).boundingBox();
    if (!box || box.width < 50 || box.height < 50) fail(`${id} is not drawn (${JSON.stringify(box)})`);
  }
  console.log(`FIGURES lines=${methodLines} diagrams=${diagrams} bins=${bins} radii=${radii} bars=${bars} heat=${heat}`);
  phase('figures');
  if (screenshot) await page.screenshot({ path: screenshot, fullPage: true });
} catch (error) {
  console.log(`FAIL: ${error.message}`);
  status = 1;
} finally {
  if (context) await context.close().catch(() => {});
  clearTimeout(overall);
}
process.exit(status);

function phase(name) {
  console.log(`PHASE ${name} ok`);
}
