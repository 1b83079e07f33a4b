// The EKF correction core of papers 000 and 003 (spec MODELS.md section 1):
// n = 3 states, m = 2 measurements, the 11-step schedule
//   1 O1 = P- H^T      2 O2 = H O1       3 O3 = O2 + R     4 O4 = inv(O3)
//   5 G = O1 O4        6 O5 = z - h(X-)  7 O6 = G O5       8 X+ = X- + O6
//   9 O7 = G H        10 O8 = O7 P-     11 P+ = P- - O8
// on six datapaths (one per element of a 3x2 result), each with a
// pipelined binary32 multiplier and adder/subtractor, and one pipelined
// divider beside them. The papers' core has nine datapaths, one per element
// of a 3x3 result, and four dividers: here a 3x3 step's row 2 (group 2)
// runs on datapaths 3-5 in the same wave, while their units would idle, and
// one divider, fed one division a cycle, costs three cycles and saves
// three dividers. Step 4 is the determinant a d - b c on datapath 0, then
// the four divisions d/det, -b/det, -c/det, a/det (negation flips the sign
// bit), entering the divider in that order.
//
// Three steps have no wave of their own: they run on operators another
// step's wave leaves idle.
//   6 O5 = z - h(X-) (inputs only): on the adders of datapaths 0 and 1 at
//     the start of step 1, before its first sum.
//   7 O6 = G O5: inside step 9's wave (O7 = G H), on datapaths 0-2, whose
//     multipliers take O6's products at w = 2 and 3, after O7's two (group
//     2 takes datapaths 3-5 then); its sums leave two cycles after O7's
//     first six, so that wave is two cycles longer.
//   8 X+ = X- + O6: beside step 10, on the adders of datapaths 0-2,
//     presented at w = 0 (step 10's first sum enters at w = Lm + 1).
// Group 2 costs step 10 La + 1 cycles (its products enter from w = La + 1,
// so that its first sum follows group 1's last) and step 11 one.
//
// Every element is computed in the order of the software reference
// (locus_hw::run): a dot product of length k is
// ((a0 b0 + a1 b1) + a2 b2), each product and sum rounded to nearest even,
// so the core's results equal the software f32 schedule bit for bit.
//
// Processor interface (the papers' Nios II side): while not busy, write the
// input bank (X-, P-, H, R, z, h(X-); addresses below; writes to other
// addresses are ignored) with wr_en, pulse start for one cycle; `done` rises
// when X+, P+ and G are in the bank and stays high until the next start;
// read any register combinationally at rd_addr.
//
// Timing (the FSM states of the papers' Fig. 3). Let Lm, La, Ld be the
// multiplier, adder and divider latencies. After the edge that samples
// start: waiting 2 cycles, then one wave per step, each a sequence of
// state visits of (latency + 1) cycles, the +1 being the cycle whose end
// writes the bank:
//   dot product, k = 2 or 3: mult1 Lm + 1, multadd (k - 1) La + 1
//   element-wise add or subtract: add La + 2 (the operands pass the
//   datapath's operand registers: the adder has none of its own);
//   four divisions: div1 Ld + 4
//   determinant: mult1 Lm + 1, add La + 1
// In mult1 the k products enter the multiplier one per cycle and the first
// is caught as it leaves; multadd feeds the adder (p0 + p1) with p1 taken
// straight from the multiplier as it leaves (so the papers' mult2 takes no
// cycle of its own), then (sum + p2) as soon as the sum leaves the adder.
// The cycle count is the cycle-level model's (`locus hw`) with these
// latencies, a transition of one cycle, six datapaths, products forwarded,
// the steps overlapped as above and element-wise operands registered
// (locus_hw::hdl::built_config).

`include "fp_latency.vh"

module ekf_core (
    input  wire        clk,
    input  wire        rst,
    input  wire        wr_en,
    input  wire [6:0]  wr_addr,
    input  wire [31:0] wr_data,
    input  wire [6:0]  rd_addr,
    output wire [31:0] rd_data,
    input  wire        start,
    output reg         busy,
    output reg         done,
    output reg  [2:0]  state
);
    // Register bank addresses (row-major matrices).
    localparam X = 0, P = 3, H = 12, R = 18, Z = 22, HX = 24;   // inputs
    localparam O1 = 26, O2 = 32, O3 = 36, DET = 40, O4 = 41, G = 45,
               O5 = 51, O6 = 53, XP = 56, O7 = 59, O8 = 68, PP = 77;
    localparam NREG = 86;
    // Datapaths: one per element of a 3x2 result; a 3x3 result's row 2
    // (group 2) runs on datapaths 3-5 in the same wave.
    localparam integer NL = 6;

    // The papers' FSM states (the `state` output).
    localparam [2:0] S_WAITING = 3'd0, S_MULT1 = 3'd1, S_MULT2 = 3'd2,
                     S_MULTADD = 3'd3, S_ADD = 3'd4, S_DIV1 = 3'd5;

    localparam integer LM = `FP_MUL_LAT, LA = `FP_ADD_LAT, LD = `FP_DIV_LAT;
    // First cycle of multadd (or of the determinant's add) in a wave: the
    // second product leaves the multiplier.
    localparam integer SUM0 = LM + 1;

    // The steps (one wave each) and the kind of each.
    localparam [3:0] T_O1 = 4'd0, T_O2 = 4'd1, T_O3 = 4'd2, T_DET = 4'd3,
                     T_O4 = 4'd4, T_G = 4'd5, T_O5 = 4'd6, T_O6 = 4'd7,
                     T_XP = 4'd8, T_O7 = 4'd9, T_O8 = 4'd10, T_PP = 4'd11;
    localparam [2:0] K_DOT3 = 3'd0, K_DOT2 = 3'd1, K_ADD = 3'd2, K_SUB = 3'd3,
                     K_DIV = 3'd4, K_DET = 3'd5;

    function [2:0] kind_of(input [3:0] step);
        case (step)
            T_O1, T_O2, T_O8:       kind_of = K_DOT3;
            T_G, T_O6, T_O7:        kind_of = K_DOT2;
            T_O3, T_XP:             kind_of = K_ADD;
            T_O5, T_PP:             kind_of = K_SUB;
            T_O4:                   kind_of = K_DIV;
            default:                kind_of = K_DET;
        endcase
    endfunction

    // O6's second product leaves the multiplier, and its sum enters the
    // adder, at this cycle of step 9's wave.
    localparam integer O6_SUM = LM + 3;

    // Group 2 of step 10 (elements 6-8 on datapaths 3-5): its products
    // enter the multipliers from this cycle on, so that its first sum
    // enters the adder one cycle after group 1's last.
    localparam integer G2 = LA + 1;

    // Cycles of each step's wave.
    function [5:0] length_of(input [3:0] step);
        if (step == T_O7)
            length_of = O6_SUM + LA + 1;
        else if (step == T_O8)
            length_of = SUM0 + 3 * LA + 2;
        else if (step == T_PP)
            length_of = LA + 3;
        else case (kind_of(step))
            K_DOT3:        length_of = SUM0 + 2 * LA + 1;
            K_DOT2, K_DET: length_of = SUM0 + LA + 1;
            K_DIV:         length_of = LD + 4;
            default:       length_of = LA + 2;
        endcase
    endfunction

    // The step whose result register `r` is, and the datapath computing it
    // (element index within the result); -1: an input register.
    function integer owner_step(input integer r);
        if (r >= PP) owner_step = T_PP;
        else if (r >= O8) owner_step = T_O8;
        else if (r >= O7) owner_step = T_O7;
        else if (r >= XP) owner_step = T_XP;
        else if (r >= O6) owner_step = T_O6;
        else if (r >= O5) owner_step = T_O5;
        else if (r >= G) owner_step = T_G;
        else if (r >= O4) owner_step = T_O4;
        else if (r >= DET) owner_step = T_DET;
        else if (r >= O3) owner_step = T_O3;
        else if (r >= O2) owner_step = T_O2;
        else if (r >= O1) owner_step = T_O1;
        else owner_step = -1;
    endfunction

    function integer owner_base(input integer r);
        case (owner_step(r))
            T_PP: owner_base = PP;   T_O8: owner_base = O8;
            T_O7: owner_base = O7;   T_XP: owner_base = XP;
            T_O6: owner_base = O6;   T_O5: owner_base = O5;
            T_G:  owner_base = G;    T_O4: owner_base = O4;
            T_DET: owner_base = DET; T_O3: owner_base = O3;
            T_O2: owner_base = O2;   default: owner_base = O1;
        endcase
    endfunction

    // ---- control ---------------------------------------------------------
    reg [3:0] step;
    reg [5:0] w;          // cycle within the wave (or within waiting)
    reg       waiting;    // the two waiting cycles after start
    wire [2:0] kind = kind_of(step);
    wire       last = !waiting && (w == length_of(step) - 1);
    // The product index entering the multipliers this cycle.
    wire [1:0] k = (w < 3) ? w[1:0] : 2'd0;

    // The step and cycle of the next clock: the adders' operand selects are
    // decoded from them a cycle ahead, into registers (below).
    reg [3:0] step_n;
    reg [5:0] w_n;
    always @* begin
        step_n = step;
        w_n = w + 6'd1;
        if (rst || !busy) begin
            step_n = 4'd0;
            w_n = 6'd0;
        end else if (waiting) begin
            if (w == 6'd1) w_n = 6'd0;
        end else if (last) begin
            w_n = 6'd0;
            // Steps 6-8 run inside the waves of steps 1, 9 and 10.
            if (step != T_PP) step_n = (step == T_G) ? T_O7 : step + 4'd1;
        end
    end

    always @(posedge clk) begin
        step <= step_n;
        w <= w_n;
        if (rst) begin
            busy <= 1'b0;
            done <= 1'b0;
            waiting <= 1'b0;
        end else if (!busy) begin
            if (start) begin
                busy <= 1'b1;
                done <= 1'b0;
                waiting <= 1'b1;
            end
        end else if (waiting) begin
            if (w == 6'd1) waiting <= 1'b0;
        end else if (last && step == T_PP) begin
            busy <= 1'b0;
            done <= 1'b1;
        end
    end

    // The papers' state of the current cycle (mult2 has no cycle of its
    // own: the second product enters the adder as it leaves).
    always @* begin
        if (!busy || waiting) state = S_WAITING;
        else case (kind)
            K_DOT3, K_DOT2, K_DET:
                state = (w <= LM) ? S_MULT1 :
                        (kind == K_DET) ? S_ADD : S_MULTADD;
            K_DIV:   state = S_DIV1;
            default: state = S_ADD;
        endcase
    end

    // ---- register bank ---------------------------------------------------
    wire [32*NREG-1:0] bank;
    wire [31:0] result [0:NL-1];
    // When results leave the adders other than at the end of their wave:
    // O5 (datapaths 0, 1) at w = LA of step 1; O7's group 1 at w = SUM0 +
    // LA (group 2 and O6 at the end of step 9's wave); X+ (datapaths 0-2)
    // at w = LA of step 10; O8's group 1 at w = SUM0 + 2 LA; P+'s group 1
    // at w = LA + 1.
    wire running  = busy && !waiting;
    wire o5_ready = running && step == T_O1 && w == LA;
    wire o7_ready = running && step == T_O7 && w == SUM0 + LA;
    wire xp_ready = running && step == T_O8 && w == LA;
    wire o8_ready = running && step == T_O8 && w == SUM0 + 2 * LA;
    wire pp_ready = running && step == T_PP && w == LA + 1;
    assign rd_data = (rd_addr < NREG) ? bank[32*rd_addr +: 32] : 32'd0;

    // Only the inputs take the processor's writes (a write to a result's
    // address is ignored), so a result register has one source and no
    // multiplexer in front of it. A result is written in the cycle it
    // leaves its unit: element e < NL of a step from datapath e, elements
    // 6-8 of a 3x3 step (group 2) from datapath e - 3.
    genvar r;
    generate
        for (r = 0; r < NREG; r = r + 1) begin : regs
            reg [31:0] q;
            assign bank[32*r +: 32] = q;
            if (r < O1) begin : input_reg
                always @(posedge clk)
                    if (!busy && wr_en && wr_addr == r) q <= wr_data;
            end else if (owner_step(r) == T_O5) begin : o5_reg
                always @(posedge clk) if (o5_ready) q <= result[r - O5];
            end else if (owner_step(r) == T_O6) begin : o6_reg
                always @(posedge clk)
                    if (busy && last && step == T_O7) q <= result[r - O6];
            end else if (owner_step(r) == T_XP) begin : xp_reg
                always @(posedge clk) if (xp_ready) q <= result[r - XP];
            end else if (owner_step(r) == T_O7 && r - O7 < NL) begin : o7_reg
                always @(posedge clk) if (o7_ready) q <= result[r - O7];
            end else if (owner_step(r) == T_O8 && r - O8 < NL) begin : o8_reg
                always @(posedge clk) if (o8_ready) q <= result[r - O8];
            end else if (owner_step(r) == T_PP && r - PP < NL) begin : pp_reg
                always @(posedge clk) if (pp_ready) q <= result[r - PP];
            end else if (owner_step(r) == T_O7 || owner_step(r) == T_O8 ||
                         owner_step(r) == T_PP) begin : group2_reg
                always @(posedge clk)
                    if (busy && last && step == owner_step(r))
                        q <= result[r - owner_base(r) - 3];
            end else begin : result_reg
                always @(posedge clk)
                    if (busy && last && step == owner_step(r))
                        q <= result[r - owner_base(r)];
            end
        end
    endgenerate

`define B(i) bank[32*(i) +: 32]
// Operand i0 + s k of a dot product (k = 0, 1, 2).
`define SEL(i0, s) ((k == 2'd0) ? `B(i0) : (k == 2'd1) ? `B((i0) + (s)) : `B((i0) + 2 * (s)))

    // ---- the divider -----------------------------------------------------
    // Step 4's entries of adj(O3) = [d, -b; -c, a] enter the divider over
    // det one a cycle, entry j at w = j; its quotient leaves at w = j + LD.
    // Entries 0-2 are caught as they leave; entry 3 leaves in the wave's
    // last cycle, whose end writes the bank.
    reg  [31:0] div_a;
    wire [31:0] div_y;
    reg  [31:0] q0, q1, q2;
    always @* begin
        case (w)
            6'd0:    div_a = `B(O3 + 3);
            6'd1:    div_a = `B(O3 + 1) ^ 32'h8000_0000;
            6'd2:    div_a = `B(O3 + 2) ^ 32'h8000_0000;
            default: div_a = `B(O3 + 0);
        endcase
    end
    fp_div div (.clk(clk), .a_in(div_a), .b_in(`B(DET)), .y(div_y));
    always @(posedge clk) begin
        if (w == LD) q0 <= div_y;
        if (w == LD + 1) q1 <= div_y;
        if (w == LD + 2) q2 <= div_y;
    end
    wire [31:0] quotient [0:3];
    assign quotient[0] = q0;
    assign quotient[1] = q1;
    assign quotient[2] = q2;
    assign quotient[3] = div_y;

    // ---- datapaths -------------------------------------------------------
    genvar e;
    generate
        for (e = 0; e < NL; e = e + 1) begin : lane
            // Element (i, j) of a 3x2 / 2x2 result (2 columns), of a 3x3
            // result (3 columns); datapaths 3-5 also compute elements 6-8 of
            // the 3x3 results (group 2: row 2, column J3).
            localparam integer I2 = e / 2, J2 = e % 2, I3 = e / 3, J3 = e % 3;
            localparam GROUP2 = e >= 3;
            reg  [31:0] oa, ob;      // operands from the bank
            reg  [31:0] ra, rb;      // the same, registered: element-wise operands
            reg  [31:0] p0, p2;      // products caught from the multiplier
            wire [31:0] mul_y, add_y;
            // The adder's operands. Datapaths 0 and 1 subtract O5 = z - h(X-)
            // at the start of step 1, datapaths 0-2 add X+ = X- + O6 at the
            // start of step 10, both straight from the bank. In a dot
            // product's wave the adder takes (p0 + p1) at SUM0 (and at
            // G2 + LM + 1 for group 2 of step 10), O6's and group 2's
            // (p0 + p1) of step 9 at O6_SUM (their first product caught in
            // p2), and (sum + p2) otherwise. The selects are decoded a cycle
            // ahead into registers of this datapath's own, so that no decode
            // or wide fan-out stands before the adder.
            wire [2:0]  kind_n = kind_of(step_n);
            wire        o5_n = e < 2 && step_n == T_O1 && w_n == 6'd0;
            wire        xp_n = e < 3 && step_n == T_O8 && w_n == 6'd0;
            (* keep *) reg sel_o5, sel_xp, sel_elem, sel_sum0, sel_o6, add_sub;
            always @(posedge clk) begin
                sel_o5   <= o5_n;
                sel_xp   <= xp_n;
                sel_elem <= kind_n == K_ADD || kind_n == K_SUB;
                sel_sum0 <= w_n == SUM0 ||
                            (GROUP2 && step_n == T_O8 && w_n == G2 + LM + 1);
                sel_o6   <= w_n == O6_SUM;
                add_sub  <= o5_n || (!xp_n && (kind_n == K_SUB || kind_n == K_DET));
            end
            wire [31:0] add_a = sel_o5 ? `B(Z + e % 2) : sel_xp ? `B(X + e % 3) :
                                sel_elem ? ra : sel_sum0 ? p0 : sel_o6 ? p2 : add_y;
            wire [31:0] add_b = sel_o5 ? `B(HX + e % 2) : sel_xp ? `B(O6 + e % 3) :
                                sel_elem ? rb : (sel_sum0 || sel_o6) ? mul_y : p2;

            // Group 2's product index in step 10.
            wire [5:0]  w2 = w - G2;
            wire [1:0]  k2 = w2[1:0];
            always @* begin
                case (step)
                    T_O1: begin oa = `SEL(P + 3 * I2, 1);  ob = `SEL(H + 3 * J2, 1);  end
                    T_O2: begin oa = `SEL(H + 3 * I2, 1);  ob = `SEL(O1 + J2, 2);     end
                    T_O3: begin oa = `B(O2 + e % 4);       ob = `B(R + e % 4);        end
                    T_DET: begin
                        oa = (k == 2'd0) ? `B(O3 + 0) : `B(O3 + 1);
                        ob = (k == 2'd0) ? `B(O3 + 3) : `B(O3 + 2);
                    end
                    T_G:  begin oa = `SEL(O1 + 2 * I2, 1); ob = `SEL(O4 + J2, 2);     end
                    // At w = 2, 3: O6 = G O5's products on datapaths 0-2,
                    // group 2's (row 2 of G H) on datapaths 3-5.
                    T_O7: if (w == 2) begin
                              if (GROUP2) begin oa = `B(G + 4);     ob = `B(H + J3);     end
                              else        begin oa = `B(G + 2 * e); ob = `B(O5);         end
                          end else if (w == 3) begin
                              if (GROUP2) begin oa = `B(G + 5);     ob = `B(H + J3 + 3); end
                              else        begin oa = `B(G + 2 * e + 1); ob = `B(O5 + 1); end
                          end else begin
                              oa = `SEL(G + 2 * I3, 1);    ob = `SEL(H + J3, 3);
                          end
                    // From w = G2: group 2 (row 2 of O7 P) on datapaths 3-5.
                    T_O8: if (GROUP2 && w >= G2) begin
                              oa = (k2 == 2'd0) ? `B(O7 + 6) : (k2 == 2'd1) ? `B(O7 + 7) : `B(O7 + 8);
                              ob = (k2 == 2'd0) ? `B(P + J3) : (k2 == 2'd1) ? `B(P + J3 + 3) : `B(P + J3 + 6);
                          end else begin
                              oa = `SEL(O7 + 3 * I3, 1);   ob = `SEL(P + J3, 3);
                          end
                    // At w = 1: group 2 on datapaths 3-5.
                    default: if (GROUP2 && w == 1) begin
                                 oa = `B(P + e + 3);       ob = `B(O8 + e + 3);
                             end else begin
                                 oa = `B(P + e);           ob = `B(O8 + e);
                             end
                endcase
            end

            fp_mul mul (.clk(clk), .a_in(oa), .b_in(ob), .y(mul_y));
            fp_add add (.clk(clk), .a(add_a), .b(add_b), .sub(add_sub), .y(add_y));

            // Products leave the multiplier LM cycles after entering it; p1
            // goes straight into the adder. Group 2 of step 10 catches its
            // p0 and p2 G2 cycles after group 1's, once group 1 has used them.
            always @(posedge clk) begin
                ra <= oa;
                rb <= ob;
                if (w == LM || (GROUP2 && step == T_O8 && w == G2 + LM)) p0 <= mul_y;
                if (w == LM + 2 || (GROUP2 && step == T_O8 && w == G2 + LM + 2)) p2 <= mul_y;
            end

            // Step 4 writes O4's four entries only.
            assign result[e] = (kind == K_DIV) ? quotient[e % 4] : add_y;
        end
    endgenerate

`undef SEL
`undef B
endmodule
