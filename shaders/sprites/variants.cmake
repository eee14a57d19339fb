# The detection pass (compute) and the sprite quads (graphics: vertex + fragment); SHAPE=1: a
# non-disc aperture (kernels/sprites/sprites.hpp).
bokeh_shader(sprites detect detect.comp SHAPE=0)
bokeh_shader(sprites detect_shape detect.comp SHAPE=1)
bokeh_shader(sprites quad_vertex quad.vert)
bokeh_shader(sprites quad_fragment quad.frag SHAPE=0)
bokeh_shader(sprites quad_fragment_shape quad.frag SHAPE=1)
