// cgaskin serve: surgery on the playing model. The page talks to Python over a WebSocket on the
// page's own address (the JSON protocol of runtime/serve/protocol.py); Python runs the operation on
// this tab's own cgaskin.Surgery and answers with a delta (mesh_delta.js writes it in place).
//
// The scalpel comes from the pointer. Each step of a drag raycasts the skinned mesh in the pose on
// screen (three's raycast of a SkinnedMesh skins on the CPU) and sends one tear stroke: the blade a
// short segment along the view ray through the hit, its handle in front of the skin and its tip
// behind, from where the previous step's blade was to where this one is, both in the pose shown now
// (the previous hit is carried by its triangle's corners and barycentric coordinates, so it moves
// with the skin while the clip plays). One stroke is in flight at a time: moves that arrive meanwhile
// are merged into the next stroke, which starts from the last one sent.
// A click in drill mode drills along the view ray at the hit (radius: the slider, a fraction of the
// model's size; depth: four radii past the skin). In cut mode a click places the cutting plane at the
// hit, facing the way chosen in the panel (its normal the screen's horizontal: a vertical cut on
// screen, the default; its vertical; or the view direction); three.js's TransformControls gizmo then
// turns it (or moves it: the panel's gizmo mode), and the "cut" button cuts there, in the pose shown.
import * as THREE from 'three';
import { TransformControls } from 'three/addons/controls/TransformControls.js';
import { element, row, showStatus } from 'cgaskin/ui.js';
import { showWeights } from 'cgaskin/weights.js';
import { GrowableMesh, RimSlots } from 'cgaskin/mesh_delta.js';

const TOOLS = ['orbit', 'tear', 'cut', 'drill'];
const BLADE = 0.01;            // half the blade's length, of the model's diagonal
const MIN_MOVE = 3;            // pixels between two strokes (a shorter move tears nothing)

export async function startSurgery({container, canvas, view, meshes, playback, rims, panel, dilations, redraw}) {
    if (meshes.length !== 1) throw new Error(`cgaskin serve edits one skinned mesh; the model has ${meshes.length}`);
    const mesh = meshes[0], growable = new GrowableMesh(mesh), rimSlots = new RimSlots(rims.edges);
    const box = new THREE.Box3().setFromBufferAttribute(mesh.geometry.attributes.position);
    const diagonal = box.getSize(new THREE.Vector3()).length();
    // (the page's own query holds the token the server printed: the WebSocket must carry it too)
    const socket = new WebSocket(`${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/${location.search}`);
    const waiting = new Map();                 // id -> resolve of the request's promise
    const stats = {replies: [], sent: 0};
    const counts = {n_vertices: 0, n_faces: 0, n_rims: rims.count, rows: 0};
    let nextId = 1, tool = 'orbit';

    // ---- the WebSocket ----------------------------------------------------------------------------
    await new Promise((resolve, reject) => {
        socket.addEventListener('open', resolve, {once: true});
        socket.addEventListener('error', () => reject(new Error('cgaskin serve: no WebSocket to the server')), {once: true});
    });
    socket.addEventListener('message', (event) => {
        const reply = JSON.parse(event.data);
        const resolve = waiting.get(reply.id);
        waiting.delete(reply.id);
        if (resolve) resolve([reply, event.data.length]);
    });
    socket.addEventListener('close', () => showStatus(panel, 'cgaskin serve: the server closed the connection'));

    // Send {op, ...fields}; resolves with the reply (a delta already applied). Errors are replies too.
    const request = (op, fields = {}) => new Promise((resolve) => {
        const id = nextId++;
        waiting.set(id, ([reply, bytes]) => {
            if (reply.ok && reply.delta) applyDelta(reply.delta);
            stats.replies.push({op, ok: reply.ok, bytes, seconds: reply.seconds ?? null, error: reply.error ?? null,
                                rows: reply.delta ? counts.rows : 0});
            showStatus(panel, reply.ok ? `${op}: ${bytes} bytes back, ${counts.n_vertices} vertices, ` +
                                         `${counts.n_faces} faces, ${counts.n_rims} open edges` : `${op}: ${reply.error}`);
            resolve(reply);
        });
        stats.sent++;
        socket.send(JSON.stringify({id, op, ...fields}));
    });

    const hello = await request('hello');
    Object.assign(counts, {n_vertices: hello.n_vertices, n_faces: hello.n_faces});
    const applyDelta = (delta) => {
        counts.rows = growable.apply(delta).rows;
        rims.setEdges(rimSlots.apply(delta.rims, delta.rim_slots));
        Object.assign(counts, {n_vertices: delta.n_vertices, n_faces: delta.n_faces, n_rims: delta.n_rims});
        if (panel.weightJoint.value) showWeights(meshes, panel.weightJoint.value);
        panel.rims.disabled = false;
        if (!panel.rims.checked && rims.on) panel.rims.checked = true;
    };

    // ---- the pose shown, and rays -----------------------------------------------------------------
    // dilations are keyed by three.js's bone names, which it sanitises and makes unique (two joints
    // may differ only in a '.' or ':'): the server takes the model's joint names, skin bone by skin bone
    const jointOfBone = new Map(mesh.skeleton.bones.map((bone, i) => [bone.name, hello.bone_joints[i]]));
    const poseFields = () => ({clip: playback.clip ? playback.clip.name : null, time: playback.time,
                               dilations: Object.fromEntries([...dilations].map(([bone, factor]) =>
                                   [jointOfBone.get(bone) ?? bone, factor]))});
    const raycaster = new THREE.Raycaster();
    const hitAt = (x, y) => {            // canvas CSS pixels -> {point, ray direction, a, b, c, barycoord}
        const rect = canvas.getBoundingClientRect();
        raycaster.setFromCamera(new THREE.Vector2(x / rect.width * 2 - 1, 1 - y / rect.height * 2), view.camera);
        mesh.skeleton.update();
        mesh.computeBoundingSphere();    // (in the pose shown: three keeps the first one it computed)
        const hit = raycaster.intersectObject(mesh, false)[0];
        if (!hit) return null;
        return {point: hit.point.clone(), direction: raycaster.ray.direction.clone(), a: hit.face.a, b: hit.face.b,
                c: hit.face.c, barycoord: hit.barycoord.clone(), x, y};
    };
    const skinned = (i) => mesh.getVertexPosition(i, new THREE.Vector3()).applyMatrix4(mesh.matrixWorld);
    const surfacePoint = (hit) => skinned(hit.a).multiplyScalar(hit.barycoord.x)
        .addScaledVector(skinned(hit.b), hit.barycoord.y).addScaledVector(skinned(hit.c), hit.barycoord.z);
    const blade = (point, direction) => {
        const half = BLADE * diagonal;
        return [point.clone().addScaledVector(direction, -half).toArray(), point.clone().addScaledVector(direction, half).toArray()];
    };

    // ---- tear: a drag is a chain of strokes, one in flight at a time ------------------------------
    // drag: {last: the previous blade's hit, pending: [x, y] or null, released: the button is up}
    let drag = null, busy = null;
    const pump = () => {
        if (busy || !drag) return;
        if (!drag.pending) {
            if (drag.released) drag = null;              // (the last move of the drag is sent)
            return;
        }
        const [x, y] = drag.pending;
        drag.pending = null;
        const hit = Math.hypot(x - drag.last.x, y - drag.last.y) < MIN_MOVE ? null : hitAt(x, y);
        if (!hit) { pump(); return; }
        const from = surfacePoint(drag.last);                // the previous hit where the skin is now
        const fields = {from: blade(from, from.clone().sub(view.camera.position).normalize()),
                        to: blade(hit.point, hit.direction), ...poseFields()};
        drag.last = hit;
        busy = request('tear', fields).then(() => { busy = null; pump(); });
    };
    const idle = async () => { while (busy) await busy; };

    const local = (event) => {
        const rect = canvas.getBoundingClientRect();
        return [event.clientX - rect.left, event.clientY - rect.top];
    };
    let down = null;
    canvas.addEventListener('pointerdown', (event) => {
        if (tool === 'orbit' || event.button !== 0 || (tool === 'cut' && gizmo.axis !== null)) return;   // (the gizmo's)
        down = local(event);
        if (tool === 'tear') {
            const hit = hitAt(...down);
            drag = hit ? {last: hit, pending: null, released: false} : null;
        }
    });
    canvas.addEventListener('pointermove', (event) => {
        if (tool !== 'tear' || !drag) return;
        drag.pending = local(event);
        pump();
    });
    canvas.addEventListener('pointerup', (event) => {
        if (tool === 'tear' && drag) {
            drag.pending = local(event);
            drag.released = true;
            pump();
        } else if (down && (tool === 'cut' || tool === 'drill')) {
            const [x, y] = local(event);
            if (Math.hypot(x - down[0], y - down[1]) < MIN_MOVE) clickTool(x, y);
        }
        down = null;
    });

    // ---- the cutting plane: a translucent square (its normal: local +z) and a gizmo on it ---------
    const plane = new THREE.Mesh(new THREE.PlaneGeometry(1, 1), new THREE.MeshBasicMaterial(
        {color: 0x4fc3f7, transparent: true, opacity: 0.35, side: THREE.DoubleSide, depthWrite: false}));
    plane.scale.setScalar(0.7 * diagonal);
    plane.visible = false;
    view.scene.add(plane);
    const gizmo = new TransformControls(view.camera, canvas);
    gizmo.setMode('rotate');
    gizmo.setSize(0.8);
    const gizmoHelper = gizmo.getHelper();
    gizmoHelper.visible = false;
    view.scene.add(gizmoHelper);
    gizmo.addEventListener('dragging-changed', (event) => { view.controls.enabled = !event.value && tool === 'orbit'; });
    gizmo.addEventListener('change', () => redraw());
    const showPlane = (on) => {
        plane.visible = gizmoHelper.visible = on;
        if (on) gizmo.attach(plane); else gizmo.detach();
        gizmo.enabled = on;
    };
    const placePlane = (hit) => {        // at the hit, facing the way the panel says
        const normal = new THREE.Vector3(), axis = controls.cutNormal.value;
        if (axis === 'view') normal.copy(hit.direction);
        else normal.setFromMatrixColumn(view.camera.matrixWorld, axis === 'vertical' ? 1 : 0);
        plane.position.copy(hit.point);
        plane.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), normal.normalize());
        plane.updateMatrixWorld(true);
        showPlane(true);
        redraw();
    };
    const cutWithPlane = () => {
        if (!plane.visible) { showStatus(panel, 'cut: click on the model to place the plane first'); return null; }
        const normal = new THREE.Vector3(0, 0, 1).applyQuaternion(plane.quaternion);
        const result = request('cut', {normal: normal.toArray(), point: plane.position.toArray(), ...poseFields()});
        busy = result.then(() => { busy = null; });
        return result;
    };

    // ---- cut and drill: a click ---------------------------------------------------------------------
    const clickTool = (x, y) => {
        const hit = hitAt(x, y);
        if (!hit) { showStatus(panel, `${tool}: the click is not on the model`); return null; }
        if (tool === 'cut') { placePlane(hit); return Promise.resolve({ok: true}); }
        const radius = Number(controls.radius.value) * diagonal, d = hit.direction;
        const result = request('drill', {start: hit.point.clone().addScaledVector(d, -(2 * radius + BLADE * diagonal)).toArray(),
                                         end: hit.point.clone().addScaledVector(d, 4 * radius).toArray(), radius,
                                         ...poseFields()});
        busy = result.then(() => { busy = null; });
        return result;
    };

    // ---- the panel ---------------------------------------------------------------------------------
    const controls = {
        tool: element('select', {id: 'tool', title: 'what a drag or click on the model does'}),
        radius: element('input', {id: 'drill-radius', type: 'range', min: '0.003', max: '0.05', step: '0.001',
                                  value: '0.015', title: 'drill radius, of the model\'s size'}),
        cutNormal: element('select', {id: 'cut-normal', title: 'which way a placed cutting plane faces'}),
        gizmoMode: element('select', {id: 'gizmo-mode', title: 'what the gizmo does to the plane'}),
        cut: element('button', {id: 'cut', type: 'button', text: 'cut'}),
        undo: element('button', {id: 'undo', type: 'button', text: 'undo'}),
        save: element('button', {id: 'save-glb', type: 'button', text: 'save .glb'}),
    };
    for (const name of TOOLS) controls.tool.appendChild(element('option', {value: name, text: name}));
    for (const [value, text] of [['horizontal', 'across the screen'], ['vertical', 'up the screen'], ['view', 'the view direction']])
        controls.cutNormal.appendChild(element('option', {value, text}));
    for (const [value, text] of [['rotate', 'turn'], ['translate', 'move']])
        controls.gizmoMode.appendChild(element('option', {value, text}));
    const setTool = (name) => {
        if (!TOOLS.includes(name)) throw new Error(`tool ${JSON.stringify(name)}: one of ${TOOLS.join(', ')}`);
        tool = name;
        controls.tool.value = name;
        if (name !== 'cut') showPlane(false);
        view.controls.enabled = name === 'orbit';          // (a drag is the scalpel's, not the camera's)
        return name;
    };
    const undo = async () => { await idle(); return request('undo'); };
    const save = async () => {
        await idle();
        const reply = await request('save');
        if (!reply.ok) return null;
        return reply;
    };
    controls.tool.addEventListener('change', () => setTool(controls.tool.value));
    controls.gizmoMode.addEventListener('change', () => gizmo.setMode(controls.gizmoMode.value));
    controls.cut.addEventListener('click', () => cutWithPlane());
    controls.undo.addEventListener('click', () => undo());
    controls.save.addEventListener('click', async () => {
        const reply = await save();
        if (!reply) return;
        const bytes = Uint8Array.from(atob(reply.glb), (c) => c.charCodeAt(0));
        const link = element('a', {download: reply.name});
        link.href = URL.createObjectURL(new Blob([bytes], {type: 'model/gltf-binary'}));
        link.click();
        setTimeout(() => URL.revokeObjectURL(link.href), 1000);
    });
    panel.status.before(element('div', {class: 'surgery'}, [
        row('tool', controls.tool, controls.undo, controls.save),
        row('drill r', controls.radius),
        row('cut', controls.cutNormal, controls.gizmoMode, controls.cut),
    ]));
    showStatus(panel, `cgaskin serve: ${hello.model}, ${hello.n_vertices} vertices; pick a tool, then drag ` +
                      `(tear) or click (cut, drill) on the model`);
    redraw();

    // the page's API (window.cgaskinView) for tests and scripts
    return {
        tools: TOOLS,
        setTool,
        counts: () => ({...counts}),
        serveStats: () => ({...stats, meshBytes: hello.mesh_bytes, diagonal}),
        surgeryPose: () => poseFields(),       // the pose an operation sends now (the model's joint names)
        serveIdle: idle,
        serveRequest: async (op, fields) => { await idle(); return request(op, fields); },
        undo: async () => (await undo()).ok,
        saveGlb: async () => { const reply = await save(); return reply ? reply.glb : null; },
        clickTool: async (x, y) => { const r = clickTool(x, y); return r ? (await r).ok : null; },
        // the plane placed (null: none), and a turn of it about an axis (radians), as the gizmo does
        cuttingPlane: () => (plane.visible ? {point: plane.position.toArray(),
                                              normal: new THREE.Vector3(0, 0, 1).applyQuaternion(plane.quaternion).toArray()} : null),
        turnPlane: (axis, angle) => {
            plane.rotateOnWorldAxis(new THREE.Vector3(...axis).normalize(), angle);
            redraw();
            return new THREE.Vector3(0, 0, 1).applyQuaternion(plane.quaternion).toArray();
        },
        cutWithPlane: async () => { await idle(); const r = cutWithPlane(); return r ? (await r).ok : null; },
    };
}
