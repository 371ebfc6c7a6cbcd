
// window.bushingServerModels: "known" once patched, "unpatched" if BokehJS has no such internals
if (window.bushingServerModels == null) {
  const mod = Bokeh.require("document")
  const proto = mod != null && mod.Document != null ? mod.Document.prototype : null
  const doc = Bokeh.documents[0]
  if (proto != null && typeof proto.apply_json_patch === "function" && doc != null && doc._new_models instanceof Set) {
    // the ids of the models a patch defines ({type: "object", id, ...} anywhere in its events)
    const defined = (value, ids) => {
      if (Array.isArray(value)) {
        for (const v of value) if (v !== null && typeof v === "object") defined(v, ids)
      } else if (value !== null && typeof value === "object" && !ArrayBuffer.isView(value)
                 && !(value instanceof ArrayBuffer)) {
        if (value.type === "object" && typeof value.id === "string") ids.add(value.id)
        for (const v of Object.values(value)) if (v !== null && typeof v === "object") defined(v, ids)
      }
      return ids
    }
    const apply = proto.apply_json_patch
    proto.apply_json_patch = function (patch, buffers) {
      apply.call(this, patch, buffers)
      if (this._new_models.size == 0) return  // nothing the page counts as new: nothing to look for
      const ids = defined(patch.events, new Set())
      for (const model of [...this._new_models]) if (ids.has(model.id)) this._new_models.delete(model)
    }
    window.bushingServerModels = "known"
  } else {
    window.bushingServerModels = "unpatched"
  }
}
