impactdic_add_benchmark(NAME dic_benchmark SOURCES dic_benchmark.cc
  DEPS impactdic::dic impactdic::synth impactdic::io TBB::tbb)
