"""The browser explorer: Panel views over a param state; the plotting API in HoloViews."""
