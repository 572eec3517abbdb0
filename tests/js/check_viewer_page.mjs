// The viewer's page in a real browser (issue 72): Debian's chromium, headless, driven by
// puppeteer-core (no browser downloaded). Loads the page of a running lab, reads what it shows
// twice, some seconds apart, and saves a screenshot.
//   node check_viewer_page.mjs http://127.0.0.1:PORT/ screenshot.png [--seconds S]
// Prints one JSON line: {first, second, errors}.
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import puppeteer from "puppeteer-core";

const [url, shot] = process.argv.slice(2);
const i = process.argv.indexOf("--seconds");
const seconds = i > 0 ? Number(process.argv[i + 1]) : 3;
const profile = fs.mkdtempSync(path.join(os.tmpdir(), "dw-viewer-chromium-"));
const browser = await puppeteer.launch({
  executablePath: process.env.DW_CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", `--user-data-dir=${profile}`],
});
const errors = [];
try {
  const page = await browser.newPage();
  page.on("pageerror", (e) => errors.push(String(e.message)));
  page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
  await page.setViewport({ width: 1480, height: 860 });
  await page.goto(url, { waitUntil: "load" });
  const read = () => page.evaluate(() => ({
    connected: window.dwView.connected,
    counts: window.dwView.counts,
    f_d: document.getElementById("value-f_d").textContent,
    vehicles: document.getElementById("vehicles").textContent,
    phase: document.getElementById("phase").textContent,
    leg: document.getElementById("leg").textContent,
    progress: document.getElementById("progress").textContent,
    processes: document.getElementById("processes").tBodies[0].rows.length,
  }));
  const sleep = (s) => new Promise((r) => setTimeout(r, s * 1000));
  await sleep(seconds);
  const first = await read();
  await sleep(seconds);
  const second = await read();
  await page.screenshot({ path: shot });
  console.log(JSON.stringify({ first, second, errors }));
} finally {
  await browser.close();
  fs.rmSync(profile, { recursive: true, force: true });
}
