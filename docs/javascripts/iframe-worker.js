/* A page opened from disk (file://) may not start a web worker, and the site's search runs in
   one. Opened from disk, this runs the worker's script in a hidden frame of the page instead,
   with the worker's messages passed by hand: the search works with no server and no network.
   (The role of the iframe-worker polyfill that the theme's offline plugin would otherwise fetch
   from the network; the subset of a Worker the theme uses: postMessage, message events,
   terminate.) Served over HTTP, the browser's own Worker is kept. */
(function () {
  "use strict";
  if (location.protocol !== "file:") return;

  class FrameWorker extends EventTarget {
    constructor(url) {
      super();
      this.onmessage = null;
      this.onerror = null;
      this.queue = [];
      this.ready = false;
      this.frame = document.createElement("iframe");
      this.frame.hidden = true;
      this.frame.setAttribute("aria-hidden", "true");
      document.body.appendChild(this.frame);
      const win = this.frame.contentWindow;
      // What the worker's script posts reaches the page as a message event of this worker.
      win.postMessage = (data) => {
        const event = new MessageEvent("message", { data: data });
        this.dispatchEvent(event);
        if (typeof this.onmessage === "function") this.onmessage(event);
      };
      win.importScripts = function () {
        throw new Error("importScripts is not available to a worker run from disk");
      };
      const script = win.document.createElement("script");
      script.src = new URL(url, location.href).href;
      script.onload = () => {
        this.ready = true;
        this.queue.splice(0).forEach((data) => this.deliver(data));
      };
      script.onerror = (event) => {
        this.dispatchEvent(new Event("error"));
        if (typeof this.onerror === "function") this.onerror(event);
      };
      win.document.head.appendChild(script);
    }

    deliver(data) {
      const win = this.frame.contentWindow;
      win.dispatchEvent(new win.MessageEvent("message", { data: data }));
    }

    postMessage(data) {
      if (this.ready) this.deliver(data);
      else this.queue.push(data);
    }

    terminate() {
      this.frame.remove();
    }
  }

  window.Worker = FrameWorker;
})();
