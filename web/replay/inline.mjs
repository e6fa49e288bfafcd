// Puts the bundled script into the page template:
//   node inline.mjs TEMPLATE.html BUNDLE.js OUT.html
// The template's <!--HYQ_REPLAY_BUNDLE--> becomes <script>BUNDLE</script>;
// its /*HYQ_REPLAY_DATA*/ stays, for hyq_sim to fill (sim_host/records/replay.cpp).
import { readFileSync, writeFileSync, renameSync } from 'node:fs';

const [templatePath, bundlePath, outPath] = process.argv.slice(2);
if (!outPath) {
  console.error('usage: node inline.mjs TEMPLATE.html BUNDLE.js OUT.html');
  process.exit(2);
}
const BUNDLE = '<!--HYQ_REPLAY_BUNDLE-->';
const DATA = '/*HYQ_REPLAY_DATA*/';
const page = readFileSync(templatePath, 'utf8');
// "</script" inside the script would end it early; "<\/script" means the same in JS strings.
const bundle = readFileSync(bundlePath, 'utf8').replaceAll('</script', '<\\/script');
const at = page.indexOf(BUNDLE);
const data = page.indexOf(DATA);
if (at < 0 || data < 0 || data > at || bundle.includes(DATA)) {
  console.error(`inline.mjs: ${templatePath}: expected ${DATA} before ${BUNDLE}, and neither in the bundle`);
  process.exit(1);
}
const out = page.slice(0, at) + '<script>' + bundle + '</script>' + page.slice(at + BUNDLE.length);
writeFileSync(outPath + '.tmp', out);
renameSync(outPath + '.tmp', outPath);
