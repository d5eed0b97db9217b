// The control panel: plain DOM, built once. Every control calls back into main.js through the
// handlers passed to buildPanel; main.js also drives the same state from window.cgaskinView (tests,
// notebooks), and writes it back here with the set* functions so the panel always tells the truth.

export function element(tag, attributes = {}, children = []) {
    const node = document.createElement(tag);
    for (const [key, value] of Object.entries(attributes)) {
        if (key === 'text') node.textContent = value;
        else node.setAttribute(key, value);
    }
    for (const child of children) node.appendChild(child);
    return node;
}

export function row(label, ...controls) {
    return element('div', {class: 'row'}, [element('span', {class: 'label', text: label}), ...controls]);
}

function options(select, names, withNone) {
    select.replaceChildren();
    if (withNone) select.appendChild(element('option', {value: '', text: withNone}));
    for (const name of names) select.appendChild(element('option', {value: name, text: name}));
}

// clips: [{name, duration}], bones: [names]; handlers: {clip, play, time, speed, loop, skeleton,
// weightJoint, dilateJoint, dilation, rims, skinning, savePng}; skinningModes: the modes, the first
// one shown `skinning`. Returns the controls by id.
export function buildPanel(root, clips, bones, rimCount, skinningModes, skinning, handlers) {
    const c = {
        clip: element('select', {id: 'clip', title: 'clip to play'}),
        play: element('button', {id: 'play', type: 'button', text: 'pause'}),
        time: element('input', {id: 'time', type: 'range', min: '0', max: '1', step: 'any', value: '0',
                                title: 'timeline: drag to set the time'}),
        timeLabel: element('span', {id: 'time-label', class: 'value', text: '0.000 s'}),
        speed: element('select', {id: 'speed', title: 'playback speed'}),
        loop: element('input', {id: 'loop', type: 'checkbox', checked: ''}),
        skeleton: element('input', {id: 'skeleton', type: 'checkbox'}),
        weightJoint: element('select', {id: 'weight-joint', title: 'colour vertices by this joint\'s weight'}),
        dilateJoint: element('select', {id: 'dilate-joint', title: 'joint to dilate'}),
        dilation: element('input', {id: 'dilation', type: 'range', min: '0.2', max: '3', step: '0.01', value: '1'}),
        dilationLabel: element('span', {id: 'dilation-label', class: 'value', text: '×1.00'}),
        rims: element('input', {id: 'rims', type: 'checkbox'}),
        skinning: element('select', {id: 'skinning', title: 'who skins the mesh: cgaskin (the bones\' versors, '
                                     + 'generated GLSL ES) or three.js (bone matrices)'}),
        savePng: element('button', {id: 'save-png', type: 'button', text: 'save PNG'}),
        status: element('div', {id: 'status'}),
        boneLabel: element('div', {id: 'bone-label', class: 'bone-label'}),
    };
    options(c.clip, clips.map((clip) => clip.name), clips.length ? null : '(no clips: rest pose)');
    for (const s of [0.25, 0.5, 1, 1.5, 2])
        c.speed.appendChild(element('option', {value: String(s), text: `${s}×`}));
    c.speed.value = '1';
    options(c.weightJoint, bones, '(off)');
    options(c.dilateJoint, bones, null);
    options(c.skinning, skinningModes, null);
    c.skinning.value = skinning;
    if (rimCount) c.rims.checked = true;
    else c.rims.disabled = true;
    // (a rim is a boundary edge of the welded mesh: a cut's open side, a slit, a hole)
    const rimText = rimCount ? `${rimCount} open edges (cuts, slits, holes)` : 'none: the surface is closed';

    root.appendChild(element('div', {class: 'panel'}, [
        row('clip', c.clip, c.play),
        row('time', c.time, c.timeLabel),
        row('speed', c.speed, element('label', {}, [c.loop, element('span', {text: ' loop'})])),
        row('skeleton', element('label', {}, [c.skeleton, element('span', {text: ' show (hover: names)'})])),
        row('weights', c.weightJoint),
        row('dilate', c.dilateJoint, c.dilation, c.dilationLabel),
        row('rims', element('label', {}, [c.rims, element('span', {text: ' ' + rimText})])),
        row('skinning', c.skinning),
        row('', c.savePng),
        c.status,
    ]));
    root.appendChild(c.boneLabel);

    c.clip.addEventListener('change', () => handlers.clip(c.clip.value));
    c.play.addEventListener('click', () => handlers.play());
    c.time.addEventListener('input', () => handlers.time(Number(c.time.value)));
    c.speed.addEventListener('change', () => handlers.speed(Number(c.speed.value)));
    c.loop.addEventListener('change', () => handlers.loop(c.loop.checked));
    c.skeleton.addEventListener('change', () => handlers.skeleton(c.skeleton.checked));
    c.weightJoint.addEventListener('change', () => handlers.weightJoint(c.weightJoint.value || null));
    c.dilateJoint.addEventListener('change', () => handlers.dilateJoint(c.dilateJoint.value));
    c.dilation.addEventListener('input', () => handlers.dilation(Number(c.dilation.value)));
    c.rims.addEventListener('change', () => handlers.rims(c.rims.checked));
    c.skinning.addEventListener('change', () => handlers.skinning(c.skinning.value));
    c.savePng.addEventListener('click', () => handlers.savePng());
    return c;
}

export function showTime(c, time, duration) {
    c.time.max = String(duration || 1);
    c.time.value = String(time);
    c.timeLabel.textContent = `${time.toFixed(3)} s`;
}

export function showPlaying(c, playing) {
    c.play.textContent = playing ? 'pause' : 'play';
}

export function showDilation(c, joint, factor) {
    c.dilateJoint.value = joint;
    c.dilation.value = String(factor);
    c.dilationLabel.textContent = `×${factor.toFixed(2)}`;
}

export function showStatus(c, text) {
    c.status.textContent = text;
}
