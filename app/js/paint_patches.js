
// window[flag] says what happened: `done` if the method was found and wrapped, else "unpatched".
const patch = (flag, done, module, cls, method, wrap) => {
  if (window[flag] != null) return
  const mod = Bokeh.require(module)
  const proto = mod != null && mod[cls] != null ? mod[cls].prototype : null
  if (proto != null && typeof proto[method] === "function") {
    proto[method] = wrap(proto[method])
    window[flag] = done
  } else {
    window[flag] = "unpatched"
  }
}
patch("bushingStyleWrites", "skip-unchanged", "core/dom", "InlineStyleSheet", "_update", (update) =>
  function (css) { if (this.el.textContent !== css) update.call(this, css) })
// A line's, a fill's or a text's CSS variables read once per task and visual. Read once for the
// visual's life instead (no theming after its first paint), the diagnosis clicked at once measured
// the same (median 2.6 s, 8 runs each, 2026-12-06): the renderer's 0.2 s of getPropertyValue per
// diagnosis moved to its other style recalculations, so the per-task cache stays
patch("bushingCssReads", "cached-per-task", "core/visuals/visual", "VisualProperties", "_get_css_value", (read) =>
  function (name) {
    if (this._bushing_css == null) {
      this._bushing_css = new Map()
      queueMicrotask(() => { this._bushing_css = null })
    }
    let value = this._bushing_css.get(name)
    if (value === undefined) {
      value = read.call(this, name)
      this._bushing_css.set(name, value)
    }
    return value
  })
patch("bushingGlyphPosition", "inline-style", "models/renderers/glyph_renderer", "GlyphRendererView", "update_position", (update) =>
  function () {
    if (this.panel != null || this.position == null) {
      return update.call(this)
    }
    if (this._bushing_inline == null) {
      this.position.replace("")  // once: what an earlier paint wrote there no longer applies
      this._bushing_inline = true
    }
    const { bbox } = this
    const style = this.el.style
    if (bbox != null && bbox.is_valid) {
      style.removeProperty("display")
      style.position = "absolute"
      style.left = `${bbox.left}px`
      style.top = `${bbox.top}px`
      style.width = `${bbox.width}px`
      style.height = `${bbox.height}px`
    } else {
      style.display = "none"
    }
  })
