// Pipeline latencies of the binary32 units, in clock cycles.
//
// A unit with latency L has L registers on every path from its inputs to y,
// the last of which drives y. Operands presented before rising edge t are
// sampled by edge t; y holds their result from just after edge t+L-1 until
// edge t+L. So y appears L rising edges after the inputs are presented,
// counting the sampling edge as the first. A new operation may be presented
// before every edge.
//
// The multiplier and the divider first register their operands (their
// stage 0): the core's schedule decode and operand multiplexers end there,
// so that no path runs from them into a unit's arithmetic (placed and
// routed, this took the core from 19 to 30 MHz; docs/hw.md). The adder does
// not: the core feeds it only from registers (products caught, the
// multiplier's and the adder's outputs, bank registers, and for
// element-wise steps its own copy of the multiplier's operand registers),
// through a multiplexer of a few inputs, so a stage 0 would cost a cycle a
// sum for nothing.
`ifndef FP_LATENCY_VH
`define FP_LATENCY_VH
`define FP_MUL_LAT 3
`define FP_ADD_LAT 3
`define FP_DIV_LAT 13
`endif
