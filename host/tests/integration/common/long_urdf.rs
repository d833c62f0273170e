//! A URDF chain of `n` revolute joints with a link mass each, for the size tests and the
//! `scaling` benchmark (which includes this file).

/// The chain `l0 -> l1 -> ... -> ln`, joints `j1..jn`.
pub fn long_urdf(n: usize) -> String {
    let mut s = String::from("<robot name=\"long\">\n<link name=\"l0\"/>\n");
    for k in 1..=n {
        s.push_str(&format!(
            "<link name=\"l{k}\"><inertial><mass value=\"0.1\"/><origin xyz=\"0.01 0 0\"/></inertial></link>\n\
             <joint name=\"j{k}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{k}\"/>\
             <origin xyz=\"0.001 0 0.001\" rpy=\"0 0.1 0\"/><axis xyz=\"0 0 1\"/>\
             <limit lower=\"-1\" upper=\"1\"/></joint>\n",
            k - 1
        ));
    }
    s.push_str("</robot>\n");
    s
}
