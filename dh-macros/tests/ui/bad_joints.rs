aacmm_dh_macros::dh_chain! {
    mod arm { joints = 0 }
}

aacmm_dh_macros::dh_chain! {
    mod arm2 { joints = 6, jionts = 6 }
}

aacmm_dh_macros::dh_chain! {
    mod arm3 { joints = "RRQR" }
}

fn main() {}
