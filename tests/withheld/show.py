import json, os, sys
D = os.environ.get('WITHHELD_DIR', os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'target', 'withheld'))
for cid in sys.argv[1:]:
    t=json.load(open(f'{D}/truth/{cid}.json')); r=json.load(open(f'{D}/results/{cid}.json'))
    print('=====',cid, t['protocol'], 'noise',t['noise'], 'scale',t['scale'])
    print(' truth params', json.dumps(t['effect_params']))
    print(' imprint(baseline fit, heldout)/noise', round(t.get('imprint_heldout_over_noise',0),1), 'raw per effect', t.get('raw_imprint_heldout_over_noise'))
    o=r['out']
    if not o: print(' NO OUTPUT', open(f'{D}/results/{cid}.err').read()[:500]); continue
    v=o['verdict']; b=o['baseline']
    print(' baseline', b['params'], 'gap_rel', b.get('gap_rel'), 'heldout', b.get('gap_heldout_rel'), 'elastic_mismatch', b.get('elastic_mismatch'), 'yield_out_of_reach', b.get('yield_out_of_reach'))
    print(' verdict', {k:v[k] for k in v if k not in ('steps',)})
    for e in o['effects'][:12]:
        print('   eff', e.get('model'), 'before %.4g after %.4g after/noise %.2f'%(e['gap_before_rel'],e['gap_after_rel'],e.get('gap_after_noise') or -1), 'below_res',e.get('below_resolution'),'fail',e.get('fit_failed'), 'at_bound', e.get('at_bound'))
    print(' steps', json.dumps(v.get('steps'))[:1500])
    print(' failed', o.get('failed'), 'holdout', o.get('holdout'))
