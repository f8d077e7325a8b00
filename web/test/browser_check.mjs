// browser_check.mjs URL OCCUPIED SCREENSHOT: loads cenote's browser viewer in Debian's headless
// Chromium (npm playwright-core driving /usr/bin/chromium, or $CHROMIUM), waits until the page
// reports OCCUPIED voxels at full detail (window.cenoteViewer), clicks a voxel, saves a screenshot,
// flies forward with the W key until the camera has moved, and prints what the page reports as JSON. Exits 1 (with the report) after TIMEOUT_S (default 120).
import { chromium } from "playwright-core";

const [url, occupiedText, screenshot] = process.argv.slice(2);
const occupied = Number(occupiedText);
const timeoutS = Number(process.env.TIMEOUT_S ?? 120);
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"],
});
const page = await browser.newPage({ viewport: { width: 960, height: 600 } });
const errors = [];
page.on("pageerror", (e) => errors.push(String(e)));
page.on("console", (m) => m.type() === "error" && errors.push(m.text()));
let code = 0;
let report = null;
try {
  await page.goto(url);
  await page.waitForFunction(
    (n) => window.cenoteViewer && window.cenoteViewer.voxels === n && window.cenoteViewer.coarseBlocks === 0 &&
      window.cenoteViewer.stats && window.cenoteViewer.stats.occupied === n,
    occupied,
    { timeout: timeoutS * 1000, polling: 250 },
  );
  await page.click("#fit");
  await page.waitForTimeout(1000);
  // Click the middle of the view (the middle of the map); the panel says what it hit.
  await page.mouse.click(620, 300);
  await page.waitForTimeout(300);
} catch (e) {
  errors.push(String(e));
  code = 1;
}
report = await page.evaluate(() => ({
  ...window.cenoteViewer,
  picked: document.getElementById("picked").textContent,
  statsPanel: document.getElementById("stats").innerText,
  connection: document.getElementById("connection").textContent,
}));
await page.screenshot({ path: screenshot });
// Then fly: W held until the camera has moved (however slowly this machine draws frames),
// and how long it was held, page clock, for the speed bound.
if (code === 0) {
  try {
    const start = await page.evaluate(() => performance.now());
    await page.keyboard.down("KeyW");
    await page.waitForFunction(() => window.cenoteViewer.flownMetres > 0.05, null, { timeout: timeoutS * 1000 });
    await page.keyboard.up("KeyW");
    report.flyHeldSeconds = ((await page.evaluate(() => performance.now())) - start) / 1000;
    report.flownMetres = await page.evaluate(() => window.cenoteViewer.flownMetres);
  } catch (e) {
    errors.push(String(e));
    code = 1;
  }
}
await browser.close();
process.stdout.write(JSON.stringify({ ...report, errors }) + "\n");
process.exit(code);
