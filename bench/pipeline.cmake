impactdic_add_benchmark(NAME python_overhead_benchmark SOURCES python_overhead_benchmark.cc
  DEPS impactdic::pipeline impactdic::io)
