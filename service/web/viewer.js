// The stex serve viewer: a hand-written canvas slippy map over /api/tiles (no libraries). The view state is
// in the URL (?model=&seed=&mni=&z=&x=&y=[&w=&h=]; x, y: the output pixel at zoom z under the canvas's top-left
// corner), so a view can be linked and the headless test can pan by URL. Tiles are drawn at integer
// offsets without smoothing: on screen every pixel is the served pixel. Zoom level z is scale 2^z; below 0
// the service filters texton models (S1 §5).
'use strict';
(function () {
  const T = 256, ZMIN = -10, ZMAX = 10;
  const canvas = document.getElementById('view');
  const ctx = canvas.getContext('2d');
  const el = (id) => document.getElementById(id);
  const q = new URLSearchParams(location.search);
  const st = {
    model: q.get('model') || '',
    seed: q.get('seed') || '0',
    mni: q.get('mni') || '30',
    z: Math.max(ZMIN, Math.min(ZMAX, parseInt(q.get('z') || '0', 10) || 0)),
    x: parseInt(q.get('x') || '0', 10) || 0,
    y: parseInt(q.get('y') || '0', 10) || 0,
  };
  const tiles = new Map();  // url -> {bitmap, state: 'loading'|'ok'|'error', used}
  const MAX_TILES = 400;
  let pending = 0, failed = 0, filterable = false;

  function url(tx, ty) {
    return '/api/tiles/' + encodeURIComponent(st.model) + '/' + st.z + '/' + tx + '/' + ty + '.png?seed=' +
           encodeURIComponent(st.seed) + '&mni=' + encodeURIComponent(st.mni);
  }

  function load(u, attempt) {
    const t = tiles.get(u) || { state: 'loading', used: 0 };
    tiles.set(u, t);
    pending++;
    fetch(u).then((r) => {
      if (r.status === 503 && attempt < 20) {  // overloaded: retry after the server's Retry-After
        const s = parseFloat(r.headers.get('Retry-After') || '1');
        setTimeout(() => { pending--; load(u, attempt + 1); }, 1000 * (isFinite(s) ? s : 1));
        return null;
      }
      if (!r.ok) throw new Error('HTTP ' + r.status);
      return r.blob().then((b) => createImageBitmap(b, { colorSpaceConversion: 'none', premultiplyAlpha: 'none' }))
        .then((bm) => { t.bitmap = bm; t.state = 'ok'; pending--; draw(); });
    }).catch(() => { t.state = 'error'; failed++; pending--; draw(); });
  }

  function prune() {
    if (tiles.size <= MAX_TILES) return;
    const old = [...tiles.entries()].filter((e) => e[1].state !== 'loading').sort((a, b) => a[1].used - b[1].used);
    for (let i = 0; i < old.length && tiles.size > MAX_TILES; i++) {
      if (old[i][1].bitmap) old[i][1].bitmap.close();
      tiles.delete(old[i][0]);
    }
  }

  let frame = 0;
  function draw() {
    frame++;
    const W = canvas.width, H = canvas.height;
    ctx.imageSmoothingEnabled = false;
    ctx.fillStyle = '#303030';
    ctx.fillRect(0, 0, W, H);
    if (!st.model) return status();
    const tx0 = Math.floor(st.x / T), ty0 = Math.floor(st.y / T);
    const tx1 = Math.floor((st.x + W - 1) / T), ty1 = Math.floor((st.y + H - 1) / T);
    for (let ty = ty0; ty <= ty1; ty++) {
      for (let tx = tx0; tx <= tx1; tx++) {
        const u = url(tx, ty);
        const t = tiles.get(u);
        if (!t) { load(u, 0); continue; }
        t.used = frame;
        if (t.state === 'ok') ctx.drawImage(t.bitmap, tx * T - st.x, ty * T - st.y);
      }
    }
    prune();
    status();
  }

  function status() {
    el('zoom').textContent = String(st.z);
    const f = st.z < 0 ? (filterable ? ', filtered (S1 §5)' : ', unfiltered') : '';
    el('status').textContent = 'scale 2^' + st.z + f + ' · view (' + st.x + ', ' + st.y + ') · ' +
                               (pending ? pending + ' loading' : 'ready') + (failed ? ' · ' + failed + ' failed' : '');
    document.title = 'stex viewer' + (pending ? '' : ' (ready)');
    clearTimeout(status.timer);
    status.timer = setTimeout(() => {
      const p = new URLSearchParams({ model: st.model, seed: st.seed, mni: st.mni, z: st.z, x: st.x, y: st.y });
      if (fixedW > 0 && fixedH > 0) { p.set('w', fixedW); p.set('h', fixedH); }
      history.replaceState(null, '', '?' + p.toString());
    }, 200);
  }

  // ?w=&h= fix the canvas size (embedding, screenshots: headless Chromium lays the page out in a smaller
  // viewport than the one it captures); otherwise the canvas fills the window below the toolbar.
  const fixedW = parseInt(q.get('w') || '0', 10), fixedH = parseInt(q.get('h') || '0', 10);
  function resize() {
    canvas.width = fixedW > 0 ? Math.min(fixedW, 8192) : window.innerWidth;
    canvas.height = fixedH > 0 ? Math.min(fixedH, 8192) : Math.max(1, window.innerHeight - 40);
    canvas.style.width = canvas.width + 'px';
    canvas.style.height = canvas.height + 'px';
    draw();
  }

  function zoom(dz, cx, cy) {
    const z = Math.max(ZMIN, Math.min(ZMAX, st.z + dz));
    if (z === st.z) return;
    // Keep the plane point under (cx, cy) fixed: positions scale by 2 per level.
    const f = Math.pow(2, z - st.z);
    st.x = Math.floor((st.x + cx) * f) - cx;
    st.y = Math.floor((st.y + cy) * f) - cy;
    st.z = z;
    draw();
  }

  let drag = null;
  canvas.addEventListener('pointerdown', (e) => {
    drag = { x: e.clientX, y: e.clientY };
    canvas.classList.add('drag');
    try { canvas.setPointerCapture(e.pointerId); } catch (err) { /* synthetic pointers (?drag=) have none */ }
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) return;
    const dx = Math.round(e.clientX - drag.x), dy = Math.round(e.clientY - drag.y);
    if (!dx && !dy) return;
    st.x -= dx; st.y -= dy;
    drag.x += dx; drag.y += dy;
    draw();
  });
  canvas.addEventListener('pointerup', () => { drag = null; canvas.classList.remove('drag'); });
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const r = canvas.getBoundingClientRect();
    zoom(e.deltaY < 0 ? 1 : -1, Math.round(e.clientX - r.left), Math.round(e.clientY - r.top));
  }, { passive: false });
  el('zin').onclick = () => zoom(1, canvas.width >> 1, canvas.height >> 1);
  el('zout').onclick = () => zoom(-1, canvas.width >> 1, canvas.height >> 1);
  el('seed').onchange = () => { st.seed = el('seed').value || '0'; draw(); };
  el('mni').onchange = () => { st.mni = el('mni').value || '30'; draw(); };
  el('model').onchange = () => { st.model = el('model').value; info(); draw(); };
  el('seed').value = st.seed;
  el('mni').value = st.mni;
  window.addEventListener('resize', resize);

  // ?drag=DX,DY: after loading, drags the view by (DX, DY) pixels through the canvas's own pointer handlers
  // (a pointerdown, moves in four steps, a pointerup), as a mouse would: the headless test pans this way.
  function scriptedDrag(spec) {
    const m = /^(-?\d+),(-?\d+)$/.exec(spec);
    if (!m) return;
    const dx = parseInt(m[1], 10), dy = parseInt(m[2], 10);
    const x0 = canvas.width >> 1, y0 = (canvas.height >> 1) + 40;
    const fire = (type, x, y) => canvas.dispatchEvent(new PointerEvent(type, {
      clientX: x, clientY: y, pointerId: 1, pointerType: 'mouse', isPrimary: true, buttons: 1, bubbles: true }));
    fire('pointerdown', x0, y0);
    for (let k = 1; k <= 4; k++) fire('pointermove', x0 + Math.round(dx * k / 4), y0 + Math.round(dy * k / 4));
    fire('pointerup', x0 + dx, y0 + dy);
  }

  function info() {
    filterable = false;
    if (!st.model) return;
    fetch('/api/models/' + encodeURIComponent(st.model)).then((r) => r.json())
      .then((j) => { filterable = !!j.filterable; status(); }).catch(() => {});
  }

  fetch('/api/models').then((r) => r.json()).then((j) => {
    const sel = el('model');
    for (const m of j.models) {
      if (m.error) continue;
      const o = document.createElement('option');
      o.value = m.name;
      o.textContent = m.name + ' (' + m.kind + ')';
      sel.appendChild(o);
    }
    if (!st.model && sel.options.length) st.model = sel.options[0].value;
    sel.value = st.model;
    info();
    resize();
    if (q.get('drag')) scriptedDrag(q.get('drag'));
  }).catch(() => { el('status').textContent = 'cannot list models'; resize(); });
})();
