# The detection pass (compute) and the sprite quads (graphics: vertex + fragment).
bokeh_shader(sprites detect detect.comp)
bokeh_shader(sprites quad_vertex quad.vert)
bokeh_shader(sprites quad_fragment quad.frag)
