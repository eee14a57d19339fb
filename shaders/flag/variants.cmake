# FLAG's 3D-buffer precisions, as kernels/flag/flag.cpp names them: name, GLSL image
# format, bracketed. One horizontal and one vertical pass per precision, worst case and adaptive
# (method option adaptive = on: bounded by the tile-max CoC map, shaders/common/tiles.glsl), and the
# scan binning's horizontal pass (horizontal_scan.comp).
foreach(entry IN ITEMS f32:rgba32f:0 f16:rgba16f:0 r11g11b10f:r11f_g11f_b10f:0 unorm10_bracketed:rgb10_a2:1
                       unorm16_bracketed:rgba16:1)
  string(REPLACE ":" ";" fields ${entry})
  list(GET fields 0 precision)
  list(GET fields 1 format)
  list(GET fields 2 bracketed)
  foreach(adaptive 0 1)
    set(suffix "")
    if(adaptive)
      set(suffix "_adaptive")
    endif()
    bokeh_shader(flag horizontal${suffix}_${precision} horizontal.comp LAYER_FORMAT=${format} BRACKETED=${bracketed}
                 ADAPTIVE=${adaptive})
    bokeh_shader(flag vertical${suffix}_${precision} vertical.comp LAYER_FORMAT=${format} BRACKETED=${bracketed}
                 ADAPTIVE=${adaptive})
    bokeh_shader(flag horizontal_scan${suffix}_${precision} horizontal_scan.comp LAYER_FORMAT=${format}
                 BRACKETED=${bracketed} ADAPTIVE=${adaptive})
  endforeach()
endforeach()
bokeh_shader(flag bracket bracket.comp ADAPTIVE=0)
bokeh_shader(flag bracket_adaptive bracket.comp ADAPTIVE=1)
bokeh_shader(flag downsample downsample.comp)
bokeh_shader(flag upsample upsample.comp)
bokeh_shader(flag tile_layers tile_layers.comp)
# Any convex aperture (kernels/flag/flag_shape.hpp): the shape's weights and areas, then the horizontal
# pass by chord extents or (horizontal_bins = scan) by row sections, per per-value precision (the
# vertical pass is vertical_<precision>).
bokeh_shader(flag shape_pack shape_pack.comp)
foreach(entry IN ITEMS f32:rgba32f f16:rgba16f r11g11b10f:r11f_g11f_b10f)
  string(REPLACE ":" ";" fields ${entry})
  list(GET fields 0 precision)
  list(GET fields 1 format)
  bokeh_shader(flag horizontal_shape_${precision} horizontal_shape.comp LAYER_FORMAT=${format})
  bokeh_shader(flag horizontal_shape_scan_${precision} horizontal_shape_scan.comp LAYER_FORMAT=${format})
endforeach()
# layer_buffer = registers (kernels/flag/flag_gpu.hpp): both passes fused, the layers in registers,
# rounded as the f32 or f16 buffer stores them.
bokeh_shader(flag fused_f32 fused.comp QUANTIZE_F16=0 SHAPE=0)
bokeh_shader(flag fused_f16 fused.comp QUANTIZE_F16=1 SHAPE=0)
bokeh_shader(flag fused_shape_f32 fused.comp QUANTIZE_F16=0 SHAPE=1)
bokeh_shader(flag fused_shape_f16 fused.comp QUANTIZE_F16=1 SHAPE=1)
