"""Compares two URDF files as XML trees (a consumer rigctl did not write: Python's ElementTree).

usage: urdf_tree.py ORIGINAL.urdf EXPORTED.urdf JOINT1,JOINT2,...

Prints one JSON object: `same_elsewhere` (every element of the original, with its attributes,
text and children in order, is in the export unchanged, except the <origin> of the listed
joints), `changed_origins` (listed joints whose origin differs), `added` (top-level elements of
the export that the original lacks, as "tag:name"), `removed` (the reverse).
"""
import json
import sys
import xml.etree.ElementTree as ET


def canon(e, skip_origin_of):
    """A comparable form of element e (origins of the named joints left out)."""
    children = []
    for c in e:
        if (
            e.tag == "joint"
            and e.get("name") in skip_origin_of
            and c.tag == "origin"
        ):
            continue
        children.append(canon(c, skip_origin_of))
    return (e.tag, sorted(e.attrib.items()), (e.text or "").strip(), (e.tail or "").strip(), children)


def key(e):
    return f"{e.tag}:{e.get('name')}"


def main() -> None:
    a, b, joints = sys.argv[1], sys.argv[2], set(sys.argv[3].split(","))
    ra, rb = ET.parse(a).getroot(), ET.parse(b).getroot()
    ka = [key(e) for e in ra]
    kb = [key(e) for e in rb]
    added = [k for k in kb if k not in ka]
    removed = [k for k in ka if k not in kb]
    kept_b = [e for e in rb if key(e) in ka]
    same = (
        ra.tag == rb.tag
        and sorted(ra.attrib.items()) == sorted(rb.attrib.items())
        and [canon(e, joints) for e in ra] == [canon(e, joints) for e in kept_b]
    )
    changed = []
    by_name_a = {e.get("name"): e for e in ra if e.tag == "joint"}
    by_name_b = {e.get("name"): e for e in rb if e.tag == "joint"}
    for j in sorted(joints):
        oa = by_name_a.get(j, ET.Element("x")).find("origin")
        ob = by_name_b.get(j, ET.Element("x")).find("origin")
        da = None if oa is None else sorted(oa.attrib.items())
        db = None if ob is None else sorted(ob.attrib.items())
        if da != db:
            changed.append(j)
    print(json.dumps({"same_elsewhere": same, "changed_origins": changed, "added": added, "removed": removed}))


if __name__ == "__main__":
    main()
