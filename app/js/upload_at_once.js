
if (window.bushingUploadAtOnce == null) {
  const model = Bokeh.Models.get("panel.models.file_dropper.FileDropper")
  const proto = model?.prototype?.default_view?.prototype
  if (proto != null && typeof proto._process_upload === "function") {
    const sent = new WeakSet()  // files already sent, whose FilePond process only completes them
    const send = proto._process_upload
    proto._process_upload = function (file, load, error, progress) {
      if (!sent.has(file)) return send.call(this, file, load, error, progress)
      sent.delete(file)
      progress(true, file.size, file.size)
      load(file.name)
      return Promise.resolve({abort: () => {}})
    }
    const viewOf = (root) => {  // the FileDropper view whose FilePond has this root element
      const seen = new Set()
      const walk = (view) => {
        if (seen.has(view)) return null
        seen.add(view)
        if (view._file_pond != null && view._file_pond.element === root) return view
        if (typeof view.children === "function") for (const child of view.children()) {
          const found = walk(child)
          if (found != null) return found
        }
        return null
      }
      for (const root of Bokeh.index) {
        const found = walk(root)
        if (found != null) return found
      }
      return null
    }
    document.addEventListener("FilePond:addfile", (event) => {
      const {file, error} = event.detail ?? {}
      if (error != null || file == null || !(file.file instanceof Blob)) return
      const view = viewOf(event.composedPath()[0])
      if (view == null || sent.has(file.file)) return
      sent.add(file.file)
      const none = () => {}
      send.call(view, file.file, none, none, none)
    })
    // a file chosen with Browse: FilePond's input hands it to FilePond 250 ms after the choice;
    // handed at once here (FilePond's addFiles: its checks of type and size as for a drop)
    const browsed = (root) => {
      const input = root?.querySelector?.("input.filepond--browser")
      const view = viewOf(root)
      if (input == null || view == null || input.bushingAtOnce) return
      input.bushingAtOnce = true
      // and a file is complete when its last byte has gone: FilePond's "minimum upload duration"
      // (a progress it plays over 0.75-1.5 s whatever the transfer) kept the area "busy", saying
      // "Uploading" and turning its ring (drawn by the CPU of a browser without GPU), while the
      // file's data were on the page: busy until 3.05 s after the hand-over, Chromium's CPU
      // meanwhile 1.77 s; now 1.49 s and 1.00 s (benchmarks/drop_area_busy.py, medians of 6,
      // 2026-12-06). Holding the ring still as well saves nothing measurable: Chromium's CPU
      // 1.11 s and 1.11 s with it still, 1.04 s and 1.10 s with it turning (drop_area_busy.py
      // [--still], two batches of 8 uploads each; 0.93 s against 1.08 s in one batch of 4 was noise)
      view._file_pond.setOptions({allowMinimumUploadDuration: false})
      input.addEventListener("change", (event) => {
        if (!input.files || input.files.length == 0) return
        event.stopImmediatePropagation()
        const files = Array.from(input.files)
        input.value = ""  // the same file can be chosen again, as FilePond allows
        view._file_pond.addFiles(files).catch(() => {})  // a refused file: FilePond's message in its area
      }, true)
    }
    document.addEventListener("FilePond:init", (event) => browsed(event.composedPath()[0]))
    for (const root of Bokeh.index) {  // the drop areas already there
      const walk = (view) => {
        if (view._file_pond != null) browsed(view._file_pond.element)
        if (typeof view.children === "function") for (const child of view.children()) walk(child)
      }
      walk(root)
    }
    window.bushingUploadAtOnce = "on"
  } else {
    window.bushingUploadAtOnce = "unpatched"
  }
}
