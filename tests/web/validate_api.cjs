// Validates the server's answers against its own JSON Schema (/api/v1/schema.json) with ajv:
// every endpoint kind, success and error bodies. Run by tests/web/run_schema.sh.
'use strict';
const Ajv = require('ajv');

(async () => {
  const base = process.env.VOLSTYLE_URL + '/api/v1';
  const schema = await (await fetch(base + '/schema.json')).json();
  const ajv = new Ajv({ strict: false, allErrors: true });
  ajv.addSchema(schema, 'v1');
  let checked = 0, failed = 0;
  const check = (definition, data, what) => {
    const validate = ajv.getSchema('v1#/definitions/' + definition);
    ++checked;
    if (!validate(data)) {
      ++failed;
      console.error(`FAIL ${what} against ${definition}: ${ajv.errorsText(validate.errors)}\n${JSON.stringify(data).slice(0, 400)}`);
    }
  };
  const call = async (method, path, body, expect) => {
    const res = await fetch(base + path, { method, body: typeof body === 'string' || body instanceof Uint8Array ? body : JSON.stringify(body),
                                           headers: { 'Content-Type': 'application/json' } });
    if (expect && res.status !== expect) { ++failed; console.error(`FAIL ${method} ${path}: status ${res.status}, expected ${expect}`); }
    return res;
  };
  const json = async (...a) => (await call(...a)).json();

  check('health', await json('GET', '/health', undefined, 200), 'GET /health');
  check('scenes', await json('GET', '/scenes', undefined, 200), 'GET /scenes');
  const session = await json('POST', '/sessions', { scene: 'builtin:sphere', resolution: 16 }, 201);
  check('session', session, 'POST /sessions');
  const sid = session.id;
  check('sessions', await json('GET', '/sessions', undefined, 200), 'GET /sessions');
  check('lighting', await json('GET', `/sessions/${sid}/lighting`, undefined, 200), 'GET lighting');
  check('lighting', await json('PUT', `/sessions/${sid}/lighting`, { sun: { direction: [0, 1, 0], irradiance: [4, 4, 4] }, background: [0, 0, 0] }, 200), 'PUT lighting');
  const view = await json('POST', `/sessions/${sid}/views`, { camera: { eye: [0, 0, 3], target: [0, 0, 0], width: 16, height: 16 } }, 201);
  check('view', view, 'POST views');
  const png = new Uint8Array(await (await call('GET', `/sessions/${sid}/views/${view.id}/render.png`, undefined, 200)).arrayBuffer());
  check('view', await json('PUT', `/sessions/${sid}/views/${view.id}/target`, png, 200), 'PUT target');
  const accepted = await json('POST', `/sessions/${sid}/solve`, { unknowns: ['emission'], max_iterations: 2 }, 202);
  check('job_accepted', accepted, 'POST solve');
  // Polls a job until it ends (or 30 s pass); its last JSON.
  const waitForJob = async (id) => {
    let j;
    for (let i = 0; i < 600; ++i) {
      j = await json('GET', `/jobs/${id}`, undefined, 200);
      if (['done', 'failed', 'cancelled'].includes(j.state)) break;
      await new Promise((r) => setTimeout(r, 50));
    }
    return j;
  };
  const job = await waitForJob(accepted.job);
  check('job', job, 'GET job');
  check('session', await json('POST', `/sessions/${sid}/revert`, { version: 1 }, 200), 'POST revert');
  // Errors.
  check('error', await json('GET', '/sessions/0123456789abcdef0123456789abcdef', undefined, 404), '404');
  check('error', await json('POST', '/sessions', { colour: 1 }, 400), 'unknown field');
  check('error', await json('POST', '/sessions', '{nope', 400), 'malformed JSON');
  check('error', await json('PUT', `/sessions/${sid}/lighting`, { phase: { type: 'rayleigh' } }, 400), 'bad lighting');
  check('error', await json('POST', `/sessions/${sid}/render`, { camera: { eye: [0, 0, 0], target: [0, 0, 0] } }, 400), 'bad camera');
  // The stylizer (issue #11): its scene round-trips, a mesh and a TF upload, a frame request.
  const st = `/sessions/${sid}/stylizer`;
  const scene = await json('GET', st, undefined, 200);
  check('stylizer_scene', scene, 'GET stylizer');
  scene.camera.width = 48; scene.camera.height = 27; scene.light.shadow_map_size = 512;
  check('stylizer_scene', await json('PUT', st, scene, 200), 'PUT stylizer');
  check('occluder_mesh', await json('PUT', `${st}/occluders/quad`, 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n', 200), 'PUT occluder');
  check('transfer_image', await json('PUT', `${st}/tf`, png, 200), 'PUT tf');
  const frameRequest = { format: 'jpeg', aov: 'average_visibility', time: 1, method: 'naive', steps: 64 };
  check('stylizer_frame_request', frameRequest, 'a frame request');
  await call('POST', `${st}/frame`, frameRequest, 200);
  check('error', await json('PUT', `${st}/occluders/quad`, '', 422), 'empty mesh');
  // TF authoring (issue #15): a scene with layers, a pick and a clicked constraint, undo.
  scene.transfer_function = { mode: 'multiply', depth_range: [0, 40], size: [32, 32],
    layers: [{ type: 'solid', colour: [1, 1, 1] }, { type: 'diffusion', blend: 'multiply', constraints: [{ v_bar: 0.5, depth: 0.5, colour: [1, 0.5, 0] }] }] };
  check('stylizer_scene', scene, 'a scene with TF layers');
  check('stylizer_scene', await json('PUT', st, scene, 200), 'PUT stylizer with layers');
  const pick = { x: 10, y: 20 };
  check('stylizer_pick_request', pick, 'a pick');
  check('stylizer_pick', await json('POST', `${st}/pick`, pick, 200), 'POST pick');
  const constraint = { x: 24, y: 20, colour: [0.2, 0.4, 1], alpha: 1, anchor: 'world' };
  check('stylizer_constraint_request', constraint, 'a constraint request');
  check('stylizer_constraint', await json('POST', `${st}/constraints`, constraint, 200), 'POST constraints');
  check('stylizer_scene', await json('POST', `${st}/undo`, undefined, 200), 'POST undo');
  // A camera path and its sequence job.
  scene.keyframes = [{ time: 0, camera: scene.camera }, { time: 1, camera: { ...scene.camera, eye: [2, 1.7, 9] } }];
  check('stylizer_scene', await json('PUT', st, scene, 200), 'PUT stylizer with key frames');
  const sequence = { fps: 2 };
  check('stylizer_sequence_request', sequence, 'a sequence request');
  const started = await json('POST', `${st}/sequence`, sequence, 202);
  check('job_accepted', started, 'POST sequence');
  const seqJob = await waitForJob(started.job);
  check('job', seqJob, 'GET sequence job');
  if (seqJob.state !== 'done') { console.log('FAIL sequence job', JSON.stringify(seqJob)); failed++; }
  console.log(`${checked - failed} passed, ${failed} failed`);
  process.exit(failed ? 1 : 0);
})().catch((e) => { console.error('FAIL:', e.message); process.exit(1); });
