// Binomial's Basis Universal transcoder as three.js runs it (`basis_transcoder.wasm`, KTX2Loader's), transcoding a
// glTF's KTX2 images (`KHR_texture_basisu`) to RGBA32, level 0: the peer of vvgen's KTX2 decode in
// `cargo bench --bench gltf_load` (a KTX2 file's load minus that of the same file without images), same protocol:
// one untimed pass, then the median of 11. Needs, in the folder it runs from (outside the repository), `npm install
// three`; its package is found from there.
//   node PATH/TO/benches/basis_transcode.mjs FILE.gltf|FILE.glb…
import { createRequire } from 'node:module';
import { readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import vm from 'node:vm';

const from = createRequire(`${process.cwd()}/`);
const script = from.resolve('three/examples/jsm/libs/basis/basis_transcoder.js');
// A CommonJS script inside an ES-module package (three's): evaluated with a `module` of its own.
const module = { exports: {} };
const wrapped = `(function (module, exports, require, __filename, __dirname) {${readFileSync(script, 'utf8')}\n})`;
vm.runInThisContext(wrapped)(module, module.exports, from, script, dirname(script));
const BASIS = module.exports;
const basis = await BASIS({ wasmBinary: readFileSync(script.replace(/\.js$/, '.wasm')) });
basis.initializeBasis();
const RGBA32 = 13; // basist::transcoder_texture_format::cTFRGBA32

/** The KTX2 images of a .gltf (side files) or .glb (buffer views), as byte arrays. */
function ktx2Images(file) {
  const bytes = readFileSync(file);
  let json, bin;
  if (bytes.subarray(0, 4).toString() === 'glTF') {
    const length = bytes.readUInt32LE(12);
    json = JSON.parse(bytes.subarray(20, 20 + length).toString());
    bin = bytes.subarray(20 + length + 8);
  } else {
    json = JSON.parse(bytes.toString());
  }
  return (json.images ?? [])
    .filter((im) => im.mimeType === 'image/ktx2' || im.uri?.endsWith('.ktx2'))
    .map((im) => {
      if (im.uri) return new Uint8Array(readFileSync(join(dirname(file), decodeURIComponent(im.uri))));
      const v = json.bufferViews[im.bufferView];
      return new Uint8Array(bin.subarray(v.byteOffset ?? 0, (v.byteOffset ?? 0) + v.byteLength));
    });
}

function transcode(images) {
  for (const data of images) {
    const ktx2 = new basis.KTX2File(data);
    if (!ktx2.isValid() || !ktx2.startTranscoding()) throw new Error('not a Basis KTX2 image');
    const rgba = new Uint8Array(ktx2.getImageTranscodedSizeInBytes(0, 0, 0, RGBA32));
    if (!ktx2.transcodeImage(rgba, 0, 0, 0, RGBA32, 0, -1, -1)) throw new Error('transcodeImage failed');
    ktx2.close();
    ktx2.delete();
  }
}

for (const file of process.argv.slice(2)) {
  const images = ktx2Images(file);
  transcode(images);
  const times = [];
  for (let i = 0; i < 11; i++) {
    const t = performance.now();
    transcode(images);
    times.push(performance.now() - t);
  }
  times.sort((a, b) => a - b);
  console.log(`three.js basis_transcoder ${file}: ${images.length} KTX2 images in ${times[5].toFixed(1)} ms`);
}
