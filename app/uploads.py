"""The explorer's file uploads: Panel's FileDropper (FilePond in the browser).

A file larger than the readers accept (:data:`core.io.measured.MAX_BYTES`) is refused by the
browser before a byte is sent, with the limit in its message ("File is too large. Maximum file
size is 20 MB"); smaller files travel in chunks well under the websocket's message limit, so no
upload can close the session.
"""

from __future__ import annotations

from collections.abc import Callable

import panel as pn

from core.io.design_file import MAX_DESIGN_BYTES
from core.io.measured import MAX_BYTES

CHUNK_BYTES = 4 * 1024 * 1024  # per websocket message (app.main.UPLOAD_MESSAGE_BYTES allows 16 MB)
LIMIT = f"{MAX_BYTES // (1024 * 1024)}MB"


MAX_FILES = 8

# a file sent is not a file loaded: the drop area says "Sent" (not FilePond's green "Upload
# complete") and the verdict on the file is the tab's message beside it (app.state: data_message)
SENT_CSS = """
.filepond--item[data-filepond-item-state='processing-complete'] .filepond--file-status-main { font-size: 0; }
.filepond--item[data-filepond-item-state='processing-complete'] .filepond--file-status-main::after {
  content: 'Sent: the verdict is below'; font-size: 0.75rem; }
.filepond--item[data-filepond-item-state='processing-complete'] .filepond--item-panel { background-color: #5f6b7a; }
"""


def csv_dropper(multiple: bool = False) -> pn.widgets.FileDropper:
    """A drop area for one CSV file (or up to :data:`MAX_FILES`) of at most :data:`MAX_BYTES` each."""
    return pn.widgets.FileDropper(
        accepted_filetypes=[".csv", "text/csv", "text/plain"], max_file_size=LIMIT, chunk_size=CHUNK_BYTES,
        multiple=multiple, max_files=MAX_FILES if multiple else None, previews=[], layout="compact",
        sizing_mode="stretch_width", stylesheets=[SENT_CSS], **({"min_height": 90} if multiple else {"height": 90}),  # a list grows
    )


def design_dropper() -> pn.widgets.FileDropper:
    """A drop area (a click on it opens the file chooser) for one design file (.json) of at most
    :data:`core.io.design_file.MAX_DESIGN_BYTES`."""
    return pn.widgets.FileDropper(
        accepted_filetypes=[".json", "application/json"], max_file_size=f"{MAX_DESIGN_BYTES // 1000}KB",
        chunk_size=CHUNK_BYTES, multiple=False, previews=[], layout="compact", sizing_mode="stretch_width",
        height=70,
    )


def on_files(dropper: pn.widgets.FileDropper, load: Callable[[dict], object]) -> None:
    """Call ``load({filename: content, …})`` with every file in the drop area whenever the files
    change (one added, one removed: several files read as one table); an emptied area leaves the
    data loaded."""
    seen: dict[str, bytes | str] = {}

    def changed(event):
        files = dict(event.new)
        same = files.keys() == seen.keys() and all(seen[n] is c for n, c in files.items())
        if files and not same:
            seen.clear()
            seen.update(files)
            load(files)
        elif not files:
            seen.clear()

    dropper.param.watch(changed, "value")


def on_upload(dropper: pn.widgets.FileDropper, load: Callable[[bytes | str, str], object]) -> None:
    """Call ``load(content, filename)`` with the file dropped (the newest one when the drop area
    replaces an earlier file; an empty file too: it gets its message)."""
    on_files(dropper, lambda files: load(*reversed(list(files.items())[-1])))


def verdict_html(message: str, note: str = "", kind: str = "data") -> str:
    """A file's verdict as every tab shows it: a refusal (``message``, red, class
    ``{kind}-error``) and a warning or note (``note``, amber, class ``{kind}-note``)."""
    return "".join([f'<div class="{kind}-error" style="color:#b03a2e">⚠ {message}</div>' if message else "",
                     f'<div class="{kind}-note" style="color:#8a5a00">Note: {note}</div>' if note else ""])

