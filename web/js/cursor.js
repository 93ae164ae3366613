// The time cursor of the page's controls (play, time, speed). With the 3D viewer running, the server
// owns it (WS /api/viewer/ws) and the 3D arm follows it; without the viewer, a local clock. The
// socket carries the app's access cookie when there is one (same origin), like every fetch.

export class Cursor {
  constructor(source, duration, fps, onChange) {
    this.source = source;
    this.state = { source, t: 0, duration_s: duration, playing: false, speed: 1, available: false };
    this.fps = fps;
    this.onChange = onChange;
    this.ws = null;
    this.timer = null;
  }

  connect(t0) {
    return new Promise((resolve) => {
      const url = `${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/api/viewer/ws`;
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
        if (s.detail !== undefined) { console.warn(`3D viewer: ${s.detail}`); return; } // a refused command
        if (!s.available) { this.ws.close(); this.ws = null; fallback(); return; }
        if (!settled) {
          settled = true;
          this.send({ show: this.source, t: t0, playing: false });
          resolve(true);
          return;
        }
        if (s.source !== this.source) return; // another tab switched the 3D view
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
