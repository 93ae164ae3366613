// The time cursor of the page's controls (play, time, speed). With the 3D viewer running, the server
// owns it (WS /api/viewer/ws?view=<id>) and the 3D arm of this page's view follows it; without the
// viewer, a local clock. The socket carries the app's access cookie when there is one (same origin),
// like every fetch.

// Each page load has its own 3D view, so one visitor's actions never move another's arm; a
// `view=<id>` in the page's hash parameters shares a view on purpose (two tabs, one arm and cursor).
const VIEW_ID = /^[A-Za-z0-9_-]{1,32}$/;
const ALPHABET = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-"; // 64: one per 6 bits
const ownView = Array.from(crypto.getRandomValues(new Uint8Array(22)), (b) => ALPHABET[b & 63]).join("");

export function viewId() {
  const shared = new URLSearchParams(location.hash.split("?")[1] || "").get("view");
  return shared && VIEW_ID.test(shared) ? shared : ownView;
}

// The URL of viser's client for this page's view: the view is in the path, since viser's client
// connects to its own URL minus the query (ws://<host>/viser/<view>).
export function viserSrc() {
  return `/viser/${viewId()}/`;
}

export class Cursor {
  constructor(source, duration, fps, onChange) {
    this.source = source;
    this.state = { source, t: 0, duration_s: duration, playing: false, speed: 1, available: false };
    this.fps = fps;
    this.onChange = onChange;
    this.ws = null;
    this.timer = null;
    this.reason = null; // why the 3D view is not live, when the server said
  }

  connect(t0) {
    return new Promise((resolve) => {
      const scheme = location.protocol === "https:" ? "wss" : "ws";
      const url = `${scheme}://${location.host}/api/viewer/ws?view=${encodeURIComponent(viewId())}`;
      let settled = false;
      const fallback = () => { if (!settled) { settled = true; this._local(t0); resolve(false); } };
      try {
        this.ws = new WebSocket(url);
      } catch (_) {
        fallback();
        return;
      }
      this.ws.onmessage = (ev) => {
        const s = JSON.parse(ev.data);
        if (s.available === false) { this.reason = s.detail || null; this.ws.close(); this.ws = null; fallback(); return; }
        if (s.detail !== undefined) { console.warn(`3D viewer: ${s.detail}`); return; } // a refused command
        if (!settled) {
          settled = true;
          this.send({ show: this.source, t: t0, playing: false });
          resolve(true);
          return;
        }
        if (s.source !== this.source) return; // a tab sharing this view switched its recording
        this.state = s;
        this.onChange(s);
      };
      this.ws.onerror = fallback;
      this.ws.onclose = () => { if (!settled) fallback(); };
      setTimeout(fallback, 3000);
    });
  }

  send(cmd) {
    if (this.ws && this.ws.readyState === WebSocket.OPEN) {
      this.ws.send(JSON.stringify(cmd));
      return;
    }
    // local clock
    if (cmd.speed !== undefined) this.state.speed = cmd.speed;
    if (cmd.t !== undefined) this.state.t = Math.min(Math.max(cmd.t, 0), this.state.duration_s);
    if (cmd.playing !== undefined) {
      if (cmd.playing && this.state.t >= this.state.duration_s) this.state.t = 0;
      this.state.playing = cmd.playing;
    }
    this.onChange({ ...this.state });
  }

  _local(t0) {
    this.state.t = t0;
    let last = performance.now();
    this.timer = setInterval(() => {
      const now = performance.now();
      const dt = (now - last) / 1000;
      last = now;
      if (!this.state.playing) return;
      this.state.t = Math.min(this.state.t + dt * this.state.speed, this.state.duration_s);
      if (this.state.t >= this.state.duration_s) this.state.playing = false;
      this.onChange({ ...this.state });
    }, 50);
    this.onChange({ ...this.state });
  }

  seek(t) { this.send({ t }); }
  play() { this.send({ playing: true }); }
  pause() { this.send({ playing: false }); }
  speed(x) { this.send({ speed: x }); }

  close() {
    if (this.ws) this.ws.close();
    if (this.timer) clearInterval(this.timer);
  }
}
