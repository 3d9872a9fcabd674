impactdic_add_benchmark(NAME render_benchmark SOURCES render_benchmark.cc DEPS impactdic::render)
