// Opens flowsteer's report pages in headless Chromium (Debian's, through playwright-core) and
// checks what a person would see: no console error or uncaught exception, every plot drawn (an
// SVG with a line, or its note where there is nothing to draw) at a size, every picture decoded,
// every link to a file resolving (a linked page opened and checked too), each sortable table
// sorted by a click on a number column and on a text column, both ways. Saves a screenshot of
// each page into SHOTS_DIR.
//
//   node check_report.mjs SHOTS_DIR PAGE.html... [--expect-problem TEXT]
//
// --expect-problem: the pages must name TEXT among what they could not read (a run folder with
// a file missing); otherwise no page may have problems. Exits 1 with every failure listed.
import { chromium } from "playwright-core";
import { existsSync, mkdirSync } from "node:fs";
import { basename, dirname, resolve } from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";

const args = process.argv.slice(2);
const expectAt = args.indexOf("--expect-problem");
const expectedProblem = expectAt >= 0 ? args.splice(expectAt, 2)[1] : null;
const [shotsDir, ...pages] = args;
if (!shotsDir || pages.length === 0) {
  console.error("usage: node check_report.mjs SHOTS_DIR PAGE.html... [--expect-problem TEXT]");
  process.exit(2);
}
mkdirSync(shotsDir, { recursive: true });

const failures = [];
const fail = (page, what) => failures.push(`${page}: ${what}`);

async function checkPlots(page, name) {
  const plots = await page.$$eval("svg.plot", (svgs) =>
    svgs.map((svg) => {
      const box = svg.getBoundingClientRect();
      const lines = Array.from(svg.querySelectorAll("path.series")).filter(
        (p) => (p.getAttribute("d") || "").length > 2 && p.getTotalLength() > 0);
      return {
        title: svg.getAttribute("aria-label"),
        width: box.width,
        height: box.height,
        lines: lines.length,
        note: svg.querySelector("text.note") !== null,
      };
    }));
  for (const p of plots) {
    if (!(p.width > 100 && p.height > 100)) fail(name, `plot "${p.title}" is ${p.width}x${p.height} px`);
    if (p.lines === 0 && !p.note) fail(name, `plot "${p.title}" has no line and no note`);
  }
  return plots.length;
}

async function checkPictures(page, name) {
  const pictures = await page.$$eval("img", (imgs) =>
    imgs.map((img) => ({ alt: img.alt, width: img.naturalWidth, complete: img.complete })));
  for (const p of pictures) {
    if (!p.complete || p.width === 0) fail(name, `picture "${p.alt}" was not decoded`);
  }
  return pictures.length;
}

// Every relative link names a file that exists; linked pages are returned to be checked.
async function checkLinks(page, name, file) {
  const hrefs = await page.$$eval("a[href]", (as) => as.map((a) => a.getAttribute("href")));
  const linked = [];
  for (const href of hrefs) {
    const target = fileURLToPath(new URL(href, pathToFileURL(file)));
    if (!existsSync(target)) fail(name, `link ${href} leads nowhere (${target})`);
    else if (target.endsWith(".html")) linked.push(target);
  }
  return { count: hrefs.length, linked };
}

// Sorts every sortable table by its first number column and by its first column, each twice,
// and checks the order of the cells after each click.
async function checkSorting(page, name) {
  const tables = await page.$$("table.sortable");
  for (const [t, table] of tables.entries()) {
    const numberColumn = await table.evaluate((el) =>
      Array.from(el.tBodies[0].rows[0]?.cells ?? []).findIndex(
        (c) => c.dataset.sort !== undefined && c.dataset.sort !== ""));
    for (const column of [numberColumn, 0]) {
      if (column < 0) continue;
      for (const direction of ["ascending", "descending"]) {
        await table.$$eval("thead th", (ths, c) => ths[c].click(), column);
        const state = await table.evaluate((el, c) => ({
          sort: el.tHead.rows[0].cells[c].getAttribute("aria-sort"),
          keys: Array.from(el.tBodies[0].rows).map((r) => r.cells[c].dataset.sort),
          texts: Array.from(el.tBodies[0].rows).map((r) => r.cells[c].textContent),
        }), column);
        if (state.sort !== direction) fail(name, `table ${t} column ${column}: aria-sort ${state.sort} after a click for ${direction}`);
        const sign = direction === "ascending" ? 1 : -1;
        for (let k = 1; k < state.keys.length; k++) {
          const numeric = state.keys[k] !== undefined && state.keys[k - 1] !== undefined;
          const a = numeric ? (state.keys[k - 1] === "" ? Infinity : Number(state.keys[k - 1])) : state.texts[k - 1];
          const b = numeric ? (state.keys[k] === "" ? Infinity : Number(state.keys[k])) : state.texts[k];
          const order = numeric ? (a === b ? 0 : a < b ? -1 : 1) : a.localeCompare(b);
          if (sign * order > 0) fail(name, `table ${t} column ${column} not ${direction} at row ${k}: ${a} then ${b}`);
        }
      }
    }
  }
  return tables.length;
}

async function checkPage(browser, file, checked) {
  const name = basename(dirname(file)) + "/" + basename(file);
  const page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
  const errors = [];
  page.on("console", (message) => { if (message.type() === "error") errors.push(message.text()); });
  page.on("pageerror", (error) => errors.push(String(error)));
  await page.goto(pathToFileURL(file).href, { waitUntil: "load" });
  const plots = await checkPlots(page, name);
  const pictures = await checkPictures(page, name);
  const links = await checkLinks(page, name, file);
  const tables = await checkSorting(page, name);
  const problems = await page.$$eval(".problems li", (lis) => lis.map((li) => li.textContent));
  if (expectedProblem === null && problems.length > 0) fail(name, `says it could not read: ${problems.join("; ")}`);
  if (expectedProblem !== null && !problems.some((p) => p.includes(expectedProblem))) {
    fail(name, `does not name "${expectedProblem}" among what it could not read (${problems.join("; ") || "nothing"})`);
  }
  for (const e of errors) fail(name, `console error: ${e}`);
  const shot = resolve(shotsDir, name.replace(/[^A-Za-z0-9_.-]+/g, "_").replace(/\.html$/, ".png"));
  await page.screenshot({ path: shot, fullPage: true });
  console.log(`${name}: ${plots} plots, ${pictures} pictures, ${links.count} links, ${tables} sortable tables, ${errors.length} console errors -> ${shot}`);
  await page.close();
  checked.add(file);
  for (const next of links.linked) {
    if (!checked.has(next)) await checkPage(browser, next, checked);
  }
}

const executablePath = process.env.CHROMIUM ?? "/usr/bin/chromium";
const browser = await chromium.launch({ executablePath, args: ["--no-sandbox"] });
try {
  const checked = new Set();
  for (const file of pages) await checkPage(browser, resolve(file), checked);
} finally {
  await browser.close();
}
if (failures.length > 0) {
  console.error(`check_report: ${failures.length} failures\n` + failures.join("\n"));
  process.exit(1);
}
console.log("check_report: passed");
