// stac label's page in a real browser (Debian's chromium, headless, driven by puppeteer-core):
// the questions are listed and drawn, keys answer them, bad answers are refused with a message,
// and answering the last question trains a round whose new questions the page then shows.
// Usage: [LABEL_SCREENSHOT=FILE.png] node label_page.mjs URL. Prints one JSON line of what it saw;
// exits 1 on a failure.
import puppeteer from "puppeteer-core";

const url = process.argv[2];
const fail = (what) => { console.error(`label_page: ${what}`); process.exit(1); };
if (!url) fail("usage: node label_page.mjs URL");

const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"],
});
const seen = {};
try {
  const page = await browser.newPage();
  const errors = [];
  page.on("pageerror", (e) => errors.push(e.message));
  // The server's Content-Security-Policy must let the page's own script and style run.
  page.on("console", (m) => { if (/Content Security Policy/i.test(m.text())) errors.push(m.text()); });
  await page.goto(url);
  await page.waitForFunction(() => window.stacLabel && window.stacLabel.drawn > 0, { timeout: 30000 });

  const state = await page.evaluate(() => window.stacLabel.state);
  seen.classes = state.classes;
  seen.rounds_before = state.rounds;
  seen.questions_before = state.questions.length;
  const items = await page.$$eval("#questions li", (lis) => lis.map((li) => li.textContent));
  if (items.length !== state.questions.length || items.length === 0)
    fail(`${items.length} list items for ${state.questions.length} questions`);
  // Every view is drawn: coloured pixels (points, path) beyond the white ground and the grey grid.
  const inked = await page.evaluate(() => {
    const count = (canvas) => {
      const d = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height).data;
      let n = 0;
      for (let i = 0; i < d.length; i += 4) {
        const [r, g, b] = [d[i], d[i + 1], d[i + 2]];
        if (Math.max(r, g, b) - Math.min(r, g, b) > 40) ++n;  // not white, not grey
      }
      return n;
    };
    const out = {};
    for (const id of ["top", "side", "front", "path"]) out[id] = count(document.getElementById(id));
    out.snapshots = [...document.querySelectorAll("canvas.snapshot")].map(count);
    return out;
  });
  seen.inked = inked;
  for (const id of ["top", "side", "front", "path"])
    if (inked[id] < 20) fail(`the ${id} view is blank (${inked[id]} coloured pixels)`);
  if (inked.snapshots.length === 0 || inked.snapshots.some((n) => n < 5))
    fail(`segments over time: ${JSON.stringify(inked.snapshots)}`);
  if (process.env.LABEL_SCREENSHOT) {  // docs/img/label_page.png (docs/learning.md)
    await page.setViewport({ width: 1400, height: 900 });
    await page.screenshot({ path: process.env.LABEL_SCREENSHOT });
  }
  const predicted = await page.$eval("#predicted", (e) => e.textContent);
  const confidence = Number(await page.$eval("#confidence", (e) => e.textContent));
  if (![...state.classes, "background"].includes(predicted)) fail(`predicted ${predicted}`);
  if (!(confidence >= 0 && confidence <= 1)) fail(`confidence ${confidence}`);
  const buttons = await page.$$eval("#buttons button", (bs) => bs.map((b) => b.dataset.label || b.id));
  seen.buttons = buttons;
  if (JSON.stringify(buttons) !== JSON.stringify([...state.classes, "background", "skip", "train"]))
    fail(`buttons ${JSON.stringify(buttons)}`);

  // Answers by key: 1 (the first class) for the first question, then b, s, 2, ... in turn.
  const keys = ["1", "b", "s", "2"];
  seen.answers = [];
  for (let i = 0; i < state.questions.length; ++i) {
    // The page shows the next open question once the last answer is saved and drawn.
    await page.waitForFunction(() => {
      const p = window.stacLabel;
      return !p.busy && p.current >= 0 && !p.questions[p.current].answer;
    }, { timeout: 10000 });
    const q = await page.evaluate(() => {
      const p = window.stacLabel;
      const q = p.questions[p.current];
      return { source: q.source, track: q.track, answer: q.answer };
    });
    if (q.answer) fail(`question ${i} shown answered`);
    const key = keys[i % keys.length];
    const before = await page.evaluate(() => window.stacLabel.state.answers);
    await page.keyboard.press(key);
    await page.waitForFunction((n) => window.stacLabel.state.answers > n, { timeout: 10000 }, before);
    seen.answers.push({ source: q.source, track: q.track, key });
    if (i === 0) {
      // Refused: a second answer to the same track, a label that is no class, and a POST that
      // is no JSON (what a form on another site could send; issue 47).
      const again = await page.evaluate(async (q) => {
        const post = async (label, type = "application/json") => {
          const r = await fetch("/api/answer", { method: "POST", headers: { "Content-Type": type },
                                                 body: JSON.stringify({ ...q, label }) });
          return { status: r.status, error: (await r.json()).error };
        };
        return [await post("car"), await post("lamppost"), await post("car", "text/plain")];
      }, { source: q.source, track: q.track });
      seen.refused = again;
      if (again[0].status !== 400 || !/answered already/.test(again[0].error))
        fail(`a second answer: ${JSON.stringify(again[0])}`);
      if (again[1].status !== 400 || !/lamppost is none of/.test(again[1].error))
        fail(`an unknown label: ${JSON.stringify(again[1])}`);
      if (again[2].status !== 403 || !/application\/json/.test(again[2].error))
        fail(`a POST of text/plain: ${JSON.stringify(again[2])}`);
    }
  }
  // The last answer started a round; its new questions replace the answered ones.
  await page.waitForFunction(() => document.body.dataset.training === "1" ||
                                    window.stacLabel.state.rounds > 0 && window.stacLabel.state.open > 0,
                             { timeout: 10000 });
  await page.waitForFunction((r) => window.stacLabel.state.rounds > r && !window.stacLabel.state.training,
                             { timeout: 300000, polling: 500 }, seen.rounds_before);
  const after = await page.evaluate(() => window.stacLabel.state);
  seen.rounds_after = after.rounds;
  seen.questions_after = after.questions.length;
  seen.open_after = after.open;
  seen.last_round = after.last_round;
  if (after.open === 0) fail("no new question after the round");
  const header = await page.$eval("#rounds", (e) => e.textContent);
  if (Number(header) !== after.rounds) fail(`header says round ${header}`);
  if (errors.length) fail(`errors on the page: ${errors.join("; ")}`);
  console.log(JSON.stringify(seen));
} finally {
  await browser.close();
}
