"""What a notebook user drives by hand: the explorer whose sliders redraw a stroke."""
