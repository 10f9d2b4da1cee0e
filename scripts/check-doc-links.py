#!/usr/bin/env python3
# Every relative link in the repository's .md files points at an existing file
# (and, for a #fragment into a .md file, at one of its headings). Run from the
# repository root: python3 scripts/check-doc-links.py
import re,os,sys,glob,subprocess
files=subprocess.run(['git','ls-files','*.md'],capture_output=True,text=True).stdout.split()
bad=0
def anchors(path):
    out=set()
    for l in open(path):
        m=re.match(r'#+\s+(.*)',l)
        if m:
            a=m.group(1).strip().lower()
            a=re.sub(r'[^\w\- ]','',a).replace(' ','-')
            out.add(a)
    return out
for f in files:
    txt=open(f).read()
    for m in re.finditer(r'\]\(([^)\s]+)\)',txt):
        t=m.group(1)
        if re.match(r'[a-z]+://',t) or t.startswith('mailto:'): continue
        path,_,frag=t.partition('#')
        target=os.path.normpath(os.path.join(os.path.dirname(f),path)) if path else f
        if not os.path.exists(target):
            print(f"{f}: missing {t}"); bad+=1; continue
        if frag and target.endswith('.md') and frag not in anchors(target):
            print(f"{f}: missing anchor {t}"); bad+=1
print("links checked in",len(files),"files;",bad,"bad"); sys.exit(1 if bad else 0)
