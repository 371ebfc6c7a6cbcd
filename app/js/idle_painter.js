
// FilePond's painter (the drop areas' animation and work loop, one for the page) asks for every
// frame from the moment filepond.min.js loads, for as long as the page is open: Chromium then
// draws 60 frames a second on a page where nothing moves. While no drop area has been touched
// for AWAKE_MS, the painter's next frame is asked IDLE_MS later instead: its work still runs
// (a server's change to a drop area is shown within IDLE_MS), and anything that happens at a
// drop area (a pointer, a key, a drag, a file chosen, FilePond's own events) wakes it at once.
if (window.bushingIdlePainter == null) {
  const AWAKE_MS = 2000, IDLE_MS = 250
  const request = window.requestAnimationFrame.bind(window)
  const cancel = window.cancelAnimationFrame.bind(window)
  let painter = null  // FilePond's tick (FilePond 4.32: `function e(t){ ... readers.forEach ... }`)
  let awakeUntil = performance.now() + AWAKE_MS
  let frame = null, timer = null  // the painter's one pending request, a frame or a wait
  const isPainter = (callback) => typeof callback === "function" && callback.name === "e" &&
    Function.prototype.toString.call(callback).includes("readers.forEach")
  const frameFor = (callback) => { frame = request((ts) => { frame = null; callback(ts) }) }
  const drop = () => {
    if (frame !== null) cancel(frame)
    if (timer !== null) clearTimeout(timer)
    frame = timer = null
  }
  window.requestAnimationFrame = function (callback) {
    if (painter === null && isPainter(callback)) {
      painter = callback
      window.bushingIdlePainter = "on"
    }
    if (callback !== painter) return request(callback)
    drop()  // FilePond asks again after a visibility change: one pending request, never two
    if (performance.now() < awakeUntil) {
      frameFor(callback)
    } else {
      timer = setTimeout(() => { timer = null; frameFor(callback) }, IDLE_MS)
    }
    return 0
  }
  const wake = () => {
    awakeUntil = performance.now() + AWAKE_MS
    if (timer !== null && painter !== null) {
      drop()
      frameFor(painter)
    }
  }
  const atDropArea = (event) => event.composedPath().some((el) => el.classList?.contains("filepond--root"))
  for (const type of ["pointerover", "pointerdown", "keydown", "change"]) {
    document.addEventListener(type, (event) => { if (atDropArea(event)) wake() }, true)
  }
  for (const type of ["dragenter", "dragover", "drop"]) document.addEventListener(type, wake, true)
  for (const type of ["init", "warning", "error", "addfilestart", "addfileprogress", "addfile", "processfilestart",
                      "processfileprogress", "processfileabort", "processfilerevert", "processfile",
                      "processfiles", "removefile", "updatefiles"]) {
    document.addEventListener(`FilePond:${type}`, wake, true)
  }
  window.bushingIdlePainter = painter === null ? "waiting" : "on"
}
