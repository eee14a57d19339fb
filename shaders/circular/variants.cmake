# Circular separable filters: intermediates f32, f16, bracketed10 (PRECISION 0, 1, 2; see
# convolution.glsl), one horizontal and one vertical pass each; the near/far split (layers) and the
# indirect dispatch sizes of the convolution passes (plan); the radius-following mode's tile lists
# (tiles) and per-field composite (composite).
set(precisions f32 f16 bracketed10)
foreach(precision IN LISTS precisions)
  list(FIND precisions ${precision} precision_id)
  bokeh_shader(circular horizontal_${precision} horizontal.comp PRECISION=${precision_id})
  bokeh_shader(circular vertical_${precision} vertical.comp PRECISION=${precision_id})
endforeach()
bokeh_shader(circular layers layers.comp)
bokeh_shader(circular plan plan.comp)
bokeh_shader(circular tiles tiles.comp)
bokeh_shader(circular composite composite.comp)
