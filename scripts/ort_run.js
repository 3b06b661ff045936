// Runs an ONNX model with onnxruntime-node and writes its first output as raw float32.
// usage: node ort_run.js model.onnx out.bin name=DxDxD=input.bin [...]
const path = require('path');
const fs = require('fs');
const ortPath = process.env.ISPLAT_ORT_NODE ||
    path.join(__dirname, '..', 'third_party', 'onnxruntime-node', 'node_modules', 'onnxruntime-node');
const ort = require(ortPath);

(async () => {
  const [model, out, ...inputs] = process.argv.slice(2);
  const feeds = {};
  for (const spec of inputs) {
    const [name, dims, file] = spec.split('=');
    const buf = fs.readFileSync(file);
    const data = new Float32Array(buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength));
    feeds[name] = new ort.Tensor('float32', data, dims.split('x').map(Number));
  }
  const session = await ort.InferenceSession.create(model, {intraOpNumThreads: 2});
  const results = await session.run(feeds);
  const first = results[session.outputNames[0]];
  fs.writeFileSync(out, Buffer.from(first.data.buffer, first.data.byteOffset, first.data.byteLength));
  console.log(JSON.stringify({output: session.outputNames[0], dims: first.dims, ort: ort.env.versions.common}));
})().catch((e) => {
  console.error(e && e.message ? e.message : e);
  process.exit(1);
});
