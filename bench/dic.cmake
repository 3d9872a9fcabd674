impactdic_add_benchmark(NAME dic_benchmark SOURCES dic_benchmark.cc
  DEPS impactdic::dic impactdic::synth impactdic::io TBB::tbb)
impactdic_add_benchmark(NAME dic_bias_benchmark SOURCES dic_bias_benchmark.cc
  DEPS impactdic::dic impactdic::synth impactdic::preprocess TBB::tbb)
impactdic_add_benchmark(NAME reference_update_benchmark SOURCES reference_update_benchmark.cc
  DEPS impactdic::dic impactdic::synth TBB::tbb)
impactdic_add_benchmark(NAME dic_throughput_benchmark SOURCES dic_throughput_benchmark.cc
  DEPS impactdic::dic impactdic::synth impactdic::io impactdic::pipeline impactdic::preprocess
  TBB::tbb)
