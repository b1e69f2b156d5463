// node bench/validate.js FILE...: the Khronos glTF validator (npm gltf-validator)
// over each file, one JSON line of counts and the first errors: the bench's
// Lambertian copies (bench/lambert.c) are this repository's exporter's output.
const fs = require('fs'), path = require('path'), v = require('gltf-validator');
(async () => {
  for (const f of process.argv.slice(2)) {
    const data = new Uint8Array(fs.readFileSync(f));
    const r = await v.validateBytes(data, {
      uri: path.basename(f), maxIssues: 0,
      externalResourceFunction: (u) => new Promise((ok, no) => fs.readFile(path.join(path.dirname(f), decodeURIComponent(u)), (e, d) => e ? no(e.toString()) : ok(new Uint8Array(d))))
    });
    const i = r.issues;
    console.log(JSON.stringify({file: f, errors: i.numErrors, warnings: i.numWarnings, infos: i.numInfos, hints: i.numHints,
      first: i.messages.filter(m => m.severity === 0).slice(0, 3).map(m => m.code + ' ' + m.pointer)}));
  }
})();
