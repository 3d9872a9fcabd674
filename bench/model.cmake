impactdic_add_benchmark(NAME model_benchmark SOURCES model_benchmark.cc DEPS impactdic::model)
