"""The plots' building blocks: the style machinery (:mod:`app.plotting.style`) and one builder
module per tab, named by the tab's title."""
