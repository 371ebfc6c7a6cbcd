"""The tabs of the explorer, one module per tab, named by its title."""
