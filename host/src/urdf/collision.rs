//! The `<collision>` elements of a URDF's links (boxes, cylinders, spheres, meshes) and the
//! `<disable_collisions>` pairs of an SRDF, as written (URDF units: m, rad). Turning them into
//! shapes is `rigctl::plan::collision`'s part; this module only reads the text.

use super::error::UrdfError;

/// A `<geometry>` of a `<collision>` element.
#[derive(Debug, Clone, PartialEq)]
pub enum CollisionGeometry {
    /// `<box size="x y z"/>` (m).
    Box { size_m: [f64; 3] },
    /// `<cylinder radius length/>` (m), axis along the element's z.
    Cylinder { radius_m: f64, length_m: f64 },
    /// `<sphere radius/>` (m).
    Sphere { radius_m: f64 },
    /// `<mesh filename scale/>`: the file as written (`package://`, `file://`, relative or
    /// absolute) and the scale (default 1 1 1).
    Mesh { filename: String, scale: [f64; 3] },
}

/// One `<collision>` of a link.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkCollision {
    /// The link's name.
    pub link: String,
    /// `<origin xyz>` (m) in the link frame.
    pub origin_xyz_m: [f64; 3],
    /// `<origin rpy>` (rad).
    pub origin_rpy_rad: [f64; 3],
    /// The shape.
    pub geometry: CollisionGeometry,
    /// 1-based line of the `<collision>` element.
    pub line: u32,
}

fn element_err(
    doc: &roxmltree::Document,
    node: roxmltree::Node,
    src: &str,
    m: String,
) -> UrdfError {
    let pos = doc.text_pos_at(node.range().start);
    UrdfError::Element {
        source_name: src.to_string(),
        line: pos.row,
        column: pos.col,
        message: m,
    }
}

fn numbers<const N: usize>(
    doc: &roxmltree::Document,
    node: roxmltree::Node,
    src: &str,
    attr: &str,
) -> Result<Option<[f64; N]>, UrdfError> {
    let Some(text) = node.attribute(attr) else {
        return Ok(None);
    };
    let parts: Vec<f64> = text
        .split_whitespace()
        .map(|p| p.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect::<Option<Vec<f64>>>()
        .unwrap_or_default();
    <[f64; N]>::try_from(parts).map(Some).map_err(|_| {
        element_err(
            doc,
            node,
            src,
            format!("`{attr}` = `{text}`: expected {N} finite numbers"),
        )
    })
}

fn child<'a, 'i>(node: roxmltree::Node<'a, 'i>, tag: &str) -> Option<roxmltree::Node<'a, 'i>> {
    node.children()
        .find(|n| n.is_element() && n.tag_name().name() == tag)
}

fn positive(
    doc: &roxmltree::Document,
    node: roxmltree::Node,
    src: &str,
    attr: &str,
) -> Result<f64, UrdfError> {
    match numbers::<1>(doc, node, src, attr)? {
        Some([v]) if v > 0.0 => Ok(v),
        _ => Err(element_err(
            doc,
            node,
            src,
            format!("<{}> needs a positive `{attr}`", node.tag_name().name()),
        )),
    }
}

fn geometry(
    doc: &roxmltree::Document,
    geom: roxmltree::Node,
    src: &str,
) -> Result<Option<CollisionGeometry>, UrdfError> {
    let Some(shape) = geom.children().find(|n| n.is_element()) else {
        return Err(element_err(doc, geom, src, "<geometry> is empty".into()));
    };
    Ok(Some(match shape.tag_name().name() {
        "box" => {
            let size_m = numbers::<3>(doc, shape, src, "size")?
                .filter(|s| s.iter().all(|v| *v > 0.0))
                .ok_or_else(|| {
                    element_err(doc, shape, src, "<box> needs a positive `size`".into())
                })?;
            CollisionGeometry::Box { size_m }
        }
        "cylinder" => CollisionGeometry::Cylinder {
            radius_m: positive(doc, shape, src, "radius")?,
            length_m: positive(doc, shape, src, "length")?,
        },
        "sphere" => CollisionGeometry::Sphere {
            radius_m: positive(doc, shape, src, "radius")?,
        },
        "mesh" => CollisionGeometry::Mesh {
            filename: shape
                .attribute("filename")
                .ok_or_else(|| element_err(doc, shape, src, "<mesh> needs a `filename`".into()))?
                .to_string(),
            scale: numbers::<3>(doc, shape, src, "scale")?.unwrap_or([1.0; 3]),
        },
        // capsules and other extensions: not read (the caller says which links have none)
        _ => return Ok(None),
    }))
}

/// Every `<collision>` of every `<link>` of URDF `text` (`source_name` names it in messages),
/// in file order. Geometries other than box, cylinder, sphere and mesh are skipped.
pub fn link_collisions(text: &str, source_name: &str) -> Result<Vec<LinkCollision>, UrdfError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| UrdfError::Xml {
        source_name: source_name.to_string(),
        message: e.to_string(),
    })?;
    let mut out = Vec::new();
    let links = doc
        .root_element()
        .children()
        .filter(|n| n.is_element() && n.tag_name().name() == "link");
    for link in links {
        let name = link.attribute("name").unwrap_or_default().to_string();
        for col in link
            .children()
            .filter(|n| n.is_element() && n.tag_name().name() == "collision")
        {
            let Some(geom) = child(col, "geometry") else {
                continue;
            };
            let (mut xyz, mut rpy) = ([0.0; 3], [0.0; 3]);
            if let Some(o) = child(col, "origin") {
                xyz = numbers::<3>(&doc, o, source_name, "xyz")?.unwrap_or(xyz);
                rpy = numbers::<3>(&doc, o, source_name, "rpy")?.unwrap_or(rpy);
            }
            if let Some(geometry) = geometry(&doc, geom, source_name)? {
                out.push(LinkCollision {
                    link: name.clone(),
                    origin_xyz_m: xyz,
                    origin_rpy_rad: rpy,
                    geometry,
                    line: doc.text_pos_at(col.range().start).row,
                });
            }
        }
    }
    Ok(out)
}

/// The `<disable_collisions link1 link2>` pairs of SRDF `text`.
pub fn srdf_disabled_pairs(
    text: &str,
    source_name: &str,
) -> Result<Vec<(String, String)>, UrdfError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| UrdfError::Xml {
        source_name: source_name.to_string(),
        message: e.to_string(),
    })?;
    let mut out = Vec::new();
    for n in doc
        .descendants()
        .filter(|n| n.is_element() && n.tag_name().name() == "disable_collisions")
    {
        match (n.attribute("link1"), n.attribute("link2")) {
            (Some(a), Some(b)) => out.push((a.to_string(), b.to_string())),
            _ => {
                return Err(element_err(
                    &doc,
                    n,
                    source_name,
                    "<disable_collisions> needs `link1` and `link2`".into(),
                ))
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_every_shape_and_the_srdf() {
        let text = r#"<robot name="r">
  <link name="a"><collision><origin xyz="0 0 0.1" rpy="0 0 1"/><geometry><box size="0.1 0.2 0.3"/></geometry></collision></link>
  <link name="b"><collision><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision>
    <collision><geometry><sphere radius="0.02"/></geometry></collision></link>
  <link name="c"><collision><geometry><mesh filename="package://p/m.stl" scale="0.001 0.001 0.001"/></geometry></collision></link>
</robot>"#;
        let c = link_collisions(text, "t.urdf").unwrap();
        assert_eq!(c.len(), 4);
        assert_eq!(c[0].origin_xyz_m, [0.0, 0.0, 0.1]);
        assert_eq!(
            c[0].geometry,
            CollisionGeometry::Box {
                size_m: [0.1, 0.2, 0.3]
            }
        );
        assert_eq!(c[2].link, "b");
        assert!(
            matches!(c[3].geometry, CollisionGeometry::Mesh { ref filename, scale } if filename == "package://p/m.stl" && scale[0] == 0.001)
        );
        let bad = text.replace("0.1 0.2 0.3", "0.1 0.2");
        assert!(link_collisions(&bad, "t.urdf")
            .unwrap_err()
            .to_string()
            .contains("t.urdf:2"));
        let srdf = r#"<robot><disable_collisions link1="a" link2="b" reason="Adjacent"/></robot>"#;
        assert_eq!(
            srdf_disabled_pairs(srdf, "s").unwrap(),
            vec![("a".to_string(), "b".to_string())]
        );
    }
}
