//! A tree model as a new URDF (`rigctl model2urdf --model TREE.toml`): links `world` (frame R)
//! and `link_1 .. link_N` (one per tree joint, in tree order), each movable joint hanging from
//! its parent joint's link (or `world`), and per tip a fixed joint `<tip>_joint` to a link named
//! as the tip, at its tool point. Joint origins are built as in [`super::export`]'s chain (the
//! constants between a joint's parent frame and its own, and its offset), so pinocchio's forward
//! kinematics of every tip link equals the tree's `rigctl fk`.

use super::error::UrdfError;
use super::export::{
    chain_frames, movable_joint_xml, not_representable, origin_of, origin_xml, xml_escape,
    Exported, OriginChange,
};
use super::frame::Frame;
use crate::model::{ModelError, Tree};

fn invalid(tree: &Tree, message: String) -> UrdfError {
    UrdfError::Model {
        source_name: tree.name.clone(),
        source: ModelError::Invalid(message),
    }
}

/// The tree as a new URDF (see the module doc).
pub fn tree_to_urdf(tree: &Tree) -> Result<Exported, UrdfError> {
    let chains = tree.chains().map_err(|source| UrdfError::Model {
        source_name: tree.name.clone(),
        source,
    })?;
    let links: Vec<String> = (1..=tree.n_joints()).map(|i| format!("link_{i}")).collect();
    for t in &tree.tips {
        if t.name == "world" || links.contains(&t.name) {
            return Err(invalid(
                tree,
                format!("tip `{}`: the name of a link the URDF writes", t.name),
            ));
        }
    }
    // every joint's frame (and each tip's tool point) at q = 0, from the chain of a tip
    // below it (the same in every such chain)
    let mut joint_frame: Vec<Option<Frame>> = vec![None; tree.n_joints()];
    let mut tool_frame = Vec::with_capacity(tree.tips.len());
    let mut not_rep: Vec<String> = Vec::new();
    for (t, model) in chains.iter().enumerate() {
        let frames = chain_frames(model, model.scale_factor());
        for (k, &j) in tree.path(t).iter().enumerate() {
            joint_frame[j].get_or_insert(frames[model.joints()[k].elem]);
        }
        tool_frame.push(frames.last().copied().unwrap_or_else(Frame::identity));
        for line in not_representable(model, true) {
            if !not_rep.contains(&line) {
                not_rep.push(line);
            }
        }
    }
    let mut text = format!(
        "<?xml version=\"1.0\"?>\n<!-- rigctl model2urdf: tree model `{}`, frame R = link world, \
         a link per tip at its tool point; m and rad -->\n<robot name=\"{}\">\n  <link \
         name=\"world\"/>\n",
        xml_escape(&tree.name).replace("--", "- -"),
        xml_escape(&tree.name)
    );
    let mut origins = Vec::new();
    let frame_of = |j: usize| joint_frame[j].unwrap_or_else(Frame::identity);
    let link_of = |p: Option<usize>| p.map_or("world", |p| links[p].as_str());
    for (i, j) in tree.joints.iter().enumerate() {
        let prev = j.parent.map_or_else(Frame::identity, frame_of);
        let o = origin_of(&prev.inverse().then(&frame_of(i)));
        let joint = crate::model::Joint {
            elem: 0,
            prismatic: j.prismatic,
            limits: j.limits,
            harmonics: Vec::new(),
        };
        text.push_str(&movable_joint_xml(
            &j.name,
            &joint,
            link_of(j.parent),
            &links[i],
            &o,
        ));
        origins.push(OriginChange {
            joint: j.name.clone(),
            before: None,
            after: o,
        });
    }
    for (t, tip) in tree.tips.iter().enumerate() {
        let o = origin_of(&frame_of(tip.joint).inverse().then(&tool_frame[t]));
        let name = xml_escape(&tip.name);
        text.push_str(&format!(
            "  <link name=\"{name}\"/>\n  <joint name=\"{name}_joint\" type=\"fixed\">\n    \
             <parent link=\"{}\"/>\n    <child link=\"{name}\"/>\n    {}\n  </joint>\n",
            links[tip.joint],
            origin_xml(&o)
        ));
        origins.push(OriginChange {
            joint: format!("{}_joint", tip.name),
            before: None,
            after: o,
        });
    }
    text.push_str("</robot>\n");
    Ok(Exported {
        text,
        origins,
        not_representable: not_rep,
    })
}
