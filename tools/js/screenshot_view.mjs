// Opens a page written by `spall view` in headless Chromium (Debian's, software WebGL) and saves
// a screenshot at each requested time, once the viewer says it has drawn that moment.
// Usage: node tools/js/screenshot_view.mjs VIEW.html OUT_PREFIX T1 [T2 ...]  -> OUT_PREFIX<Ti>.png
import { chromium } from "playwright-core";
import { pathToFileURL } from "node:url";
import { mkdtempSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";

const [page_path, prefix, ...times] = process.argv.slice(2);
if (!page_path || !prefix || times.length === 0) {
  console.error("usage: node screenshot_view.mjs VIEW.html OUT_PREFIX T1 [T2 ...]");
  process.exit(2);
}
// A fresh profile, and none of Chromium's calls home: this machine's network is closed.
const profile = mkdtempSync(join(tmpdir(), "spall-chromium-"));
const browser = await chromium.launchPersistentContext(profile, {
  executablePath: process.env.SPALL_CHROMIUM ?? "/usr/bin/chromium",
  headless: true,
  viewport: { width: 960, height: 600 },
  args: ["--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
         "--disable-quic", "--no-first-run", "--disable-background-networking", "--disable-component-update",
         "--disable-sync"],
});
let failed = false;
try {
  const page = await browser.newPage();
  page.on("pageerror", (e) => { console.error(`page error: ${e.message}`); failed = true; });
  // The page must be self-contained: anything it fetches from elsewhere is a failure.
  page.on("request", (r) => {
    if (/^(file|data|blob):/.test(r.url())) return;
    console.error(`page requested ${r.url()}`);
    failed = true;
  });
  const url = pathToFileURL(page_path).href;
  const started = Date.now();
  await page.goto(url);
  await page.waitForFunction(() => document.body.dataset.ready || document.body.dataset.error, null, { timeout: 120000 });
  console.log(`${page_path}: loaded in ${((Date.now() - started) / 1000).toFixed(1)} s`);
  console.log(`ground ${await page.evaluate(() => document.body.dataset.ground ?? "none")}`);
  for (const t of times) {
    await page.evaluate((time) => { delete document.body.dataset.shownTime; window.location.hash = `t=${time}`; }, t);
    await page.waitForFunction(() => document.body.dataset.shownTime !== undefined || document.body.dataset.error,
                               null, { timeout: 60000 });
    if (await page.evaluate(() => document.body.dataset.error)) throw new Error(await page.textContent("#status"));
    const shown = await page.evaluate(() => document.body.dataset.shownTime);
    await page.screenshot({ path: `${prefix}${t}.png` });
    console.log(`${prefix}${t}.png: t = ${shown} s; ${await page.textContent("#status")}`);
  }
} catch (e) {
  console.error(`screenshot_view: ${e.message}`);
  failed = true;
} finally {
  await browser.close();
  rmSync(profile, { recursive: true, force: true });
}
process.exit(failed ? 1 : 0);
