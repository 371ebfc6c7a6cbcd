
if (!window.bushingLabelClicks) {
  window.bushingLabelClicks = true;
  document.addEventListener('click', (event) => {
    const path = event.composedPath();
    const label = path.find(el => el instanceof Element && el.classList.contains('bk-label'));
    if (!label || !(label.parentNode instanceof ShadowRoot)) return;
    const root = label.parentNode;
    const box = [...root.children].find(el => el.matches('input[type=checkbox], .bk-body'));
    if (box && !path.includes(box) && !box.disabled && !root.host.classList.contains('bk-disabled')) box.click();
  });
}
