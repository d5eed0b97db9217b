// node run_kernels.mjs MODULE.mjs PREFIX JOBS.json OUT.json: every job {kernel, inputs: [[base64
// float64 rows, columns] per input], rows, outputs} calls <PREFIX>_<kernel> of the module on each row;
// the results (rows x outputs float64, base64) go to OUT.json in the jobs' order.
import { readFileSync, writeFileSync } from 'node:fs';
import { pathToFileURL } from 'node:url';

const [modulePath, prefix, jobsPath, outPath] = process.argv.slice(2);
const kernels = await import(pathToFileURL(modulePath).href);
const decode = (text) => {    // (a small Buffer is a view into a shared pool: copy its own bytes)
    const bytes = Buffer.from(text, 'base64');
    return new Float64Array(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength));
};
const results = [];
for (const job of JSON.parse(readFileSync(jobsPath, 'utf8'))) {
    const fn = kernels[`${prefix}_${job.kernel}`];
    if (typeof fn !== 'function') throw new Error(`${modulePath} exports no ${prefix}_${job.kernel}`);
    const inputs = job.inputs.map(([text, columns]) => [decode(text), columns]);
    const out = new Float64Array(job.rows * job.outputs);
    for (let r = 0; r < job.rows; r++) {
        // a scalar input (columns 0) is a number; an array input a row view
        const args = inputs.map(([values, columns]) => columns === 0 ? values[r]
                                                                     : values.subarray(r * columns, (r + 1) * columns));
        out.set(fn(...args), r * job.outputs);
    }
    results.push(Buffer.from(out.buffer).toString('base64'));
}
writeFileSync(outPath, JSON.stringify(results));
