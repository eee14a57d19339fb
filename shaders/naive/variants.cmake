# The naive gather: worst case (every pixel's gather bounded by the pattern's largest disc) and
# adaptive (bounded by the tile-max CoC map, method option adaptive = on).
bokeh_shader(naive gather gather.comp ADAPTIVE=0)
bokeh_shader(naive gather_adaptive gather.comp ADAPTIVE=1)
# Any other aperture (issue 23): the shape's weights, then the gather with the shape test, over the
# whole pattern or (adaptive) bounded by the tile map.
bokeh_shader(naive shape_pack shape_pack.comp)
bokeh_shader(naive gather_shape gather_shape.comp ADAPTIVE=0)
bokeh_shader(naive gather_shape_adaptive gather_shape.comp ADAPTIVE=1)
