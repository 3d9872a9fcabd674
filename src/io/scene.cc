namespace impactdic {}
