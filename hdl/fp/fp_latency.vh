// Pipeline latencies of the binary32 units, in clock cycles.
//
// A unit with latency L has L registers on every path from its inputs to y,
// the last of which drives y. Operands presented before rising edge t are
// sampled by edge t; y holds their result from just after edge t+L-1 until
// edge t+L. So y appears L rising edges after the inputs are presented,
// counting the sampling edge as the first. A new operation may be presented
// before every edge.
`ifndef FP_LATENCY_VH
`define FP_LATENCY_VH
`define FP_MUL_LAT 3
`define FP_ADD_LAT 4
`define FP_DIV_LAT 9
`endif
