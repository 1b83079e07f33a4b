// IEEE 754 binary32 multiplier: y = a * b.
//
// Round to nearest, ties to even; subnormal inputs and results (gradual
// underflow); the sign of a product is the XOR of the operands' signs,
// zeros included; any NaN operand or 0 * inf gives the canonical quiet NaN
// 0x7FC00000. Pipelined with latency `FP_MUL_LAT (3, see fp_latency.vh for
// the edge at which y appears), one operation per clock:
//   stage 0: the operands registered;
//   stage 1: classify, unpack (subnormals normalised), 24x24 product;
//   stage 2: normalise by at most one bit, round, pack.
`include "fp_latency.vh"

module fp_mul (
    input  wire        clk,
    input  wire [31:0] a_in,
    input  wire [31:0] b_in,
    output wire [31:0] y
);
`include "fp_common.vh"

    // ---- stage 0: the operands registered (fp_latency.vh says why) ----
    reg [31:0] a;
    reg [31:0] b;
    always @(posedge clk) begin
        a <= a_in;
        b <= b_in;
    end

    // Each stage is one clocked block: its combinational logic is written
    // with blocking assignments to temporaries (assigned before use on every
    // path, so they synthesise to wires) and its results go to the stage's
    // registers. This also evaluates each stage once per clock in a
    // simulator.

    // Operand classes.
    wire a_nan = (a[30:23] == 8'hFF) && (a[22:0] != 23'd0);
    wire b_nan = (b[30:23] == 8'hFF) && (b[22:0] != 23'd0);
    wire a_inf = (a[30:0] == 31'h7F80_0000);
    wire b_inf = (b[30:0] == 31'h7F80_0000);
    wire a_zero = (a[30:0] == 31'd0);
    wire b_zero = (b[30:0] == 31'd0);

    // ---- stage 1 ----
    reg               r1_special;  // a NaN, an infinity or a zero operand
    reg        [31:0] r1_spec_y;   // the result then
    reg               r1_s;
    reg signed [11:0] r1_e;        // biased exponent of product bit 46
    reg        [47:0] r1_p;        // product of the significands, in [2^46, 2^48)

    reg        [35:0] s1_ua, s1_ub;
    always @(posedge clk) begin
        s1_ua = fp_unpack(a);
        s1_ub = fp_unpack(b);
        r1_s <= a[31] ^ b[31];
        r1_e <= s1_ua[35:24] + s1_ub[35:24] - 12'd127;
        r1_p <= s1_ua[23:0] * s1_ub[23:0];

        r1_special <= 1'b1;
        if (a_nan || b_nan || (a_inf && b_zero) || (a_zero && b_inf))
            r1_spec_y <= FP_QNAN;
        else if (a_inf || b_inf)
            r1_spec_y <= {a[31] ^ b[31], 8'hFF, 23'd0};
        else if (a_zero || b_zero)
            r1_spec_y <= {a[31] ^ b[31], 31'd0};
        else begin
            r1_special <= 1'b0;
            r1_spec_y  <= 32'd0;
        end
    end

    // ---- stage 2 ----
    reg        [31:0] r2_y;

    reg        [26:0] s2_m;
    reg signed [11:0] s2_e;
    always @(posedge clk) begin
        if (r1_p[47]) begin
            s2_m = {r1_p[47:22], |r1_p[21:0]};
            s2_e = r1_e + 12'sd1;
        end else begin
            s2_m = {r1_p[46:21], |r1_p[20:0]};
            s2_e = r1_e;
        end
        r2_y <= r1_special ? r1_spec_y : fp_round_pack(r1_s, s2_e, s2_m);
    end

    assign y = r2_y;
endmodule
