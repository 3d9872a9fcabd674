impactdic_add_benchmark(NAME sensor_benchmark SOURCES sensor_benchmark.cc DEPS impactdic::sensor)
