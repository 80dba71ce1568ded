use fcc_sim::{scenario::Scenario, sim::Sim};
fn main() {
    let s = Scenario::load(std::path::Path::new("launch_configs/scenarios/hover.yaml")).unwrap();
    let mut sim = Sim::new(s).unwrap();
    while sim.t_s() < 110.9 {
        sim.tick();
        if sim.t_s() > 110.5 && (sim.t_us / 2000) % 5 == 0 {
            let st = &sim.body.state;
            println!(
                "t {:.3} pos {:.2?} vel {:.2?} w {:.2?} rotor {:.3?} motors {:.3?}",
                sim.t_s(),
                st.pos_ned_m.as_slice(),
                st.vel_ned_mps.as_slice(),
                st.omega_frd_radps.as_slice(),
                &st.rotor_speed_frac[..3],
                &sim.fc.core.motors()[..3]
            );
        }
    }
}
